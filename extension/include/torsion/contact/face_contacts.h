#pragma once
// Face contacts (docs/contact.md, "Face contacts"): a rigid shape against the inside of an FEM
// surface triangle or edge. Node contacts hold a rigid surface only at nodes; a rigid corner, an
// edge or a sphere smaller than the mesh spacing would sink between them. A face contact holds the
// face's point nearest the shape (barycentric weights w on its nodes) against the rigid point
// nearest it. Touched only by the simulation thread.
//
// Relative velocity u = sum_j w_j v_j - J V (J V the rigid point's velocity) and the end-of-step
// gap gap + dt n.u. The constraint couples three nodes, which the per-node projection of the CG
// cannot express, so it is enforced by an augmented Lagrangian (Uzawa) in the same linear solves:
// each solve adds the impulse  Lambda - rho P h  on the face (and its opposite on the rigid body),
// h = u + n gap/dt, P = I sticking, n n^T sliding (the tangential part of Lambda is then Coulomb's
// friction), rho a penalty mass; after each solve Lambda <- proj(Lambda - rho h) onto Coulomb's
// cone. The active-set loop of RigidContactSolver repeats until every active contact's end gap
// (and sticking slip) is within `gap tolerance`; Lambda carries over to the next step, so a
// resting contact starts converged. The added term rho L^T P L is symmetric positive semi-definite:
// the reduced system stays SPD.

#include <BulletCollision/CollisionShapes/btCollisionShape.h>

#include <Eigen/Core>
#include <array>
#include <map>
#include <utility>
#include <vector>

#include "torsion/contact/rigid_partner.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"

namespace torsion {

/// A face contact whose nodes free along its normal carry less than this share of its weights
/// sits the solve out (FaceContactSet::markDetermined).
inline constexpr double kDeterminedFreeWeight = 0.1;

struct FaceContact {
  enum class State { kInactive, kSlide, kStick };
  std::array<int, 3> nodes{};                         ///< the surface triangle's nodes
  Eigen::Vector3d weights = Eigen::Vector3d::Zero();  ///< barycentric; an edge contact has a 0
  /// The nodes of non-zero weight, sorted, -1 padded: the contact's identity across steps (an
  /// edge contact found from both of its triangles is one contact).
  std::array<int, 3> key{};
  int partner = -1;                                   ///< index into the solver's partners
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, from the rigid surface to the face
  double gap = 0;                                     ///< m, signed, at the start of the step
  Eigen::Vector3d lever = Eigen::Vector3d::Zero();    ///< m, rigid point minus centre of mass
  double friction = 0;                                ///< pair coefficient
  double penalty = 0;                                 ///< kg, rho
  State state = State::kInactive;
  /// N s on the face: the multiplier estimate, warm-started from the last step.
  Eigen::Vector3d multiplier = Eigen::Vector3d::Zero();
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();  ///< N s the rigid body gave the face
  int releases = 0;                                   ///< releases this step
  /// Every weighted node is prescribed along the normal this solve (held, sticking, or sliding
  /// on a parallel normal): the nodes decide, the contact sits out (an exact node constraint and
  /// a multiplier on the same motion would make the multiplier grow without bound).
  bool determined = false;
  double last_violation = 0;     ///< m, |end gap| after the previous solve of this step
  int stalls = 0;                ///< updates this step that did not reduce the violation
  int switches = 0;              ///< stick/slide switches this step
  int friction_refinements = 0;  ///< solves this step reopened to bring the friction to mu lambda
  /// kg, sliding: the friction's resistance to a slip across its direction in the next solve
  /// (its linearisation in the slip; FaceContactSet::update).
  Eigen::Matrix3d slip_resistance = Eigen::Matrix3d::Zero();
};

class FaceContactSet {
 public:
  explicit FaceContactSet(const TetMesh& mesh);

  /// Forgets last step's contacts, keeping the active ones' state and multiplier by (key,
  /// object) to warm-start this step's. `partners` are last step's.
  void beginStep(const std::vector<RigidPartner>& partners);
  /// The longest surface edge now: a triangle overlapping a box has its nodes within this of it.
  double longestEdge(const FemState& state) const;
  /// Narrow phase against one rigid object whose (start-of-step) bounds are [lo, hi]: the surface
  /// triangles of `nearby_nodes` (every node within reach + longestEdge() of the bounds) whose
  /// bounds come within `reach` get the shape's distance (face_distance.h); a point at a
  /// triangle's corner is left to the node contact; a face all of whose nodes are held is left
  /// out unless the partner is dynamic (held nodes push, never yield); a face that the predicted
  /// motion over `dt` (s) would rather hold against the shape's supporting plane facing it (a
  /// triangle just ahead of a sliding box's edge) is left to its nodes (`dt`: the solve's
  /// look-ahead, RigidContactSolver::lookahead). A triangle with a node in `glued` (per node,
  /// non-zero: anchored to this object; empty: none) is left out: where a body is glued to the
  /// object, the two are one, not in contact (at a large step the object's own corners, within
  /// reach of the glued face's neighbours, read as deep penetrations and fought the anchors).
  void detect(const FemState& state, const NodeConstraints& held,
              const std::vector<int>& nearby_nodes, const btCollisionShape& shape,
              const btTransform& transform, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
              double reach, double dt, int partner, const RigidPartner& p, double friction,
              const std::vector<char>& glued);
  const std::vector<FaceContact>& contacts() const { return contacts_; }
  /// The contacts of polyhedral shapes' corners and edges (query/feature_contacts.h) found by
  /// this step's detect(), for the convex island solve (contact/solve/): the contacts() above
  /// are what today's solver uses.
  const std::vector<FaceContact>& featureContacts() const { return features_; }
  /// The contacts, for a solve that sets their states and impulses itself (the contact-space
  /// solve, rigid_contact_coulomb.cpp).
  std::vector<FaceContact>& mutableContacts() { return contacts_; }
  /// Back to contacts as contacts() gave them (checkpoints read back from bytes): the next
  /// beginStep() takes over their states and multipliers.
  void restoreContacts(std::vector<FaceContact> contacts) {
    contacts_ = std::move(contacts);
    index_.clear();
  }
  bool empty() const { return contacts_.empty(); }
  /// Each contact's state, in contacts() order; restoreStates() sets them back (the solve's
  /// impulses are those of the states it used, FaceContactSet::update changes them after).
  std::vector<FaceContact::State> states() const;
  void restoreStates(const std::vector<FaceContact::State>& states);

  // ---- terms of the reduced solve (rigid_contact.cpp) ----
  /// Before each solve: marks the contacts whose every weighted node `prescribed_along(node, n)`.
  template <class Prescribed>
  void markDetermined(const Prescribed& prescribed_along) {
    for (FaceContact& c : contacts_) {
      double free_weight = 0;
      for (size_t j = 0; j < 3; ++j) {
        if (c.weights[static_cast<Eigen::Index>(j)] > 0 && !prescribed_along(c.nodes[j], c.normal))
          free_weight += c.weights[static_cast<Eigen::Index>(j)];
      }
      c.determined = free_weight < kDeterminedFreeWeight;
    }
  }
  /// rho of each contact: `scale` times the effective mass of its face point from the system's
  /// diagonal 3x3 blocks, 1 / sum_j w_j^2 n.(A_jj^-1 n).
  void setPenalties(const std::vector<Eigen::Matrix3d>& diagonal_blocks, double scale);
  /// Adds rho L^T P L applied to the node velocities `v` (3n, the unknowns' part) and the dynamic
  /// partners' unknowns in `q`: node parts to `node_out`, rigid parts to `rigid_out` (indexed
  /// from `rigid_offset`).
  void addProduct(const Eigen::VectorXd& v, const Eigen::VectorXd& q,
                  const std::vector<RigidPartner>& partners, int rigid_offset,
                  Eigen::VectorXd& node_out, Eigen::VectorXd& rigid_out) const;
  /// Adds L^T (Lambda - rho P h0), h0 the part of h that does not depend on the unknowns: the
  /// prescribed node velocities `prescribed`, static or kinematic partners' surface velocities
  /// and the gap closure n gap/dt.
  void addRightHandSide(const Eigen::VectorXd& prescribed,
                        const std::vector<RigidPartner>& partners, double dt, int rigid_offset,
                        Eigen::VectorXd& node_rhs, Eigen::VectorXd& rigid_rhs) const;
  /// Adds rho w_j^2 P to the nodes' diagonal blocks and rho J^T P J to dynamic partners'.
  void addPreconditioner(std::vector<Eigen::Matrix3d>& node_blocks,
                         std::vector<Eigen::Matrix<double, 6, 6>>& rigid_blocks,
                         const std::vector<RigidPartner>& partners) const;
  /// The impulse of the solve just done (Lambda - rho P h), from its velocities `v` (3n) and the
  /// partners' velocities; then subtracts sum_j w_j impulse from `node_impulse` (3n).
  void takeImpulses(const Eigen::VectorXd& v, const std::vector<RigidPartner>& partners, double dt,
                    Eigen::VectorXd& node_impulse);
  /// The Uzawa update and the active set. Returns whether another solve is needed: a contact
  /// changed state, or an active one's end gap (or sticking slip over the step) exceeds
  /// `gap_tolerance`.
  bool update(const Eigen::VectorXd& v, const std::vector<RigidPartner>& partners, double dt,
              double activation_tolerance, double gap_tolerance);
  /// The surface triangles of `node` (indices into the mesh's surfaceTriangles()): [first, last).
  std::pair<const int*, const int*> trianglesOf(int node) const {
    const auto n = static_cast<std::size_t>(node);
    return {node_triangles_.data() + node_triangle_start_[n],
            node_triangles_.data() + node_triangle_start_[n + 1]};
  }
  /// The end-of-step gap, linearised, of contact `c` with velocities `v` and the partners'.
  double endGap(const FaceContact& c, const Eigen::VectorXd& v,
                const std::vector<RigidPartner>& partners, double dt) const;

 private:
  /// After update: each sliding face's slip_resistance from the slip of the solve just done.
  void setSlipResistance(const Eigen::VectorXd& v, const std::vector<RigidPartner>& partners);
  Eigen::Vector3d relativeVelocity(const FaceContact& c, const Eigen::VectorXd& v,
                                   const Eigen::Vector3d& rigid) const;

  std::vector<Triangle> triangles_;
  std::vector<int> node_triangle_start_, node_triangles_;  // CSR: surface triangles by node
  std::vector<int> triangle_stamp_;                        // per triangle: last detect seen
  int stamp_ = 0;
  std::vector<FaceContact> contacts_;
  std::vector<FaceContact> features_;
  std::map<std::pair<std::array<int, 3>, int>, int> index_;  // (key, partner) -> contact
  struct Remembered {
    FaceContact::State state;
    Eigen::Vector3d multiplier;
  };
  std::map<std::pair<std::array<int, 3>, const btCollisionObject*>, Remembered> previous_;
};

}  // namespace torsion
