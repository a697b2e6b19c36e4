#pragma once
// The rows of an island's contact problem (docs/contact-sap.md): one row per contact point, a
// 3-row Jacobian J_i that maps the island's velocities v to the relative contact velocity
//
//     v_c,i = J_i v = (v_t1, v_t2, v_n)   (m/s, in the contact frame: two tangents, normal last)
//
// of side B's point relative to side A's, so v_n > 0 separates (plus a known offset for a
// kinematic partner, whose motion no island dof carries). J_i is a sum of terms, each a
// dense 3 x k block on k consecutive velocity dofs of one island body:
//
//   a node of a FEM body (k = 3): w R_c, w the node's barycentric weight on the contact point
//     (negative on side A), R_c the frame (rows t1, t2, n);
//   a point of a rigid body (k = 6, the twist [v; omega] about the centre of mass, world frame):
//     +-R_c [I, -[r]x], r the point's offset from the centre of mass (v_point = v + omega x r).
//
// A node against a plane is one term, a node against a face of another FEM body 1 + 3, a point
// between two rigid bodies 2, a node against a rigid body 2: one type for all. Besides J_i, a row
// carries its physical data: the Coulomb coefficient mu, the contact stiffness k (N/m), the
// dissipation time scale tau_d (s) and the signed gap phi0 (m) at the step's start, negative when
// penetrating, and the lagged normal impulse: the contact's normal impulse of the previous step,
// which bounds this step's friction (the lagged model of Castro, Han, Masterjohn 2023).
// sap_problem.h turns them into the regularisation of Castro et al. 2022.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <vector>

namespace torsion::sap {

/// A 3 x k block, k <= 6, stored inline.
using TermBlock = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, 6>;

/// A row's kind. A contact pushes along n and rubs within Coulomb's disk (the lagged model). An
/// anchor (a node held to a rigid point) is an equality in all three directions, pulling as well
/// as pushing, without a friction bound; `gap` is minus the drift along the normal (the frame's n
/// points the drift's way); mu and the lagged impulse are not used. A joint's row (one row of a
/// Bullet btTypedConstraint: rigid_joint_rows.h) is one-dimensional: only the block's n row is
/// used (t1 and t2 are zero), its impulse drives J v towards target_velocity and stays within
/// [lower, upper]; stiffness, dissipation, gap, mu and the lagged impulse are not used
/// (sap_problem.h).
enum class RowKind : std::uint8_t { kContact, kAnchor, kJoint };

struct ContactTerm {
  int body = -1;      ///< the island body (index into the problem's bodies)
  int first_dof = 0;  ///< the block's first column acts on this dof of the body
  TermBlock block;    ///< contact-frame velocity per unit dof velocity
};

struct ContactRow {
  std::vector<ContactTerm> terms;
  /// Rows t1, t2, n (world): the frame the blocks are expressed in, for turning impulses back
  /// into world vectors (impulse_world = frame^T gamma).
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();
  double mu = 0;                ///< Coulomb coefficient, >= 0
  double stiffness = 0;         ///< k, N/m, > 0
  double dissipation_time = 0;  ///< tau_d, s, >= 0
  double gap = 0;               ///< phi0, m, negative when penetrating
  /// gamma_n of this contact in the previous step's solve (N s, >= 0; SapReport::impulses(2)):
  /// friction is bounded by the disk |gamma_t| <= mu times it. 0 for a new contact, which then
  /// has no friction in its first step (docs/contact-sap.md, "Limits").
  double lagged_normal_impulse = 0;
  /// The part of v_c that no island dof moves (m/s, contact frame): the motion of a kinematic
  /// partner's point (a moving hand, a conveyor), entered as B's minus A's. v_c = J v + this.
  Eigen::Vector3d velocity_offset = Eigen::Vector3d::Zero();
  /// What the row is (RowKind): a contact, an anchor or a joint's row.
  RowKind kind = RowKind::kContact;
  /// A joint row's velocity target (m/s or rad/s along its Jacobian; RowKind::kJoint).
  double target_velocity = 0;
  /// A joint row's impulse bounds (N s or N m s; RowKind::kJoint): -inf/+inf for an equality,
  /// one of them 0 for a limit, +-the motor's largest impulse for a motor.
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  /// A joint row's compliance relative to its Delassus estimate (Bullet's constraint force mixing,
  /// RowKind::kJoint): R_n >= relative_compliance w. 0 for a rigid joint.
  double relative_compliance = 0;
};

/// A right-handed frame with rows (t1, t2, n) for unit `normal`; t1 is the normal crossed with the
/// world axis least aligned with it, so the frame is a deterministic function of the normal.
Eigen::Matrix3d contactFrame(const Eigen::Vector3d& normal);

/// Node `node` (dofs 3 node .. 3 node + 2) of `body` with weight `weight` (barycentric, signed:
/// negative on side A).
ContactTerm nodeTerm(int body, int node, double weight, const Eigen::Matrix3d& frame);

/// The point at world offset `offset` from the centre of mass of rigid `body` (6 dofs: the twist
/// [v; omega]); sign +1 on side B, -1 on side A.
ContactTerm rigidPointTerm(int body, const Eigen::Vector3d& offset, double sign,
                           const Eigen::Matrix3d& frame);

}  // namespace torsion::sap
