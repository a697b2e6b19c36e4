#pragma once
// From detection to rows (docs/contact-solve.md, "From detection to rows"): one FEM body's node
// contacts with rigid objects (RigidContactSolver::detect: NodeContact, RigidPartner) as a SAP
// island, and the solve's impulses back to the partners and to the next step's lagged values.
//
// Side A is the rigid partner, side B the node: NodeContact::normal points out of the rigid body
// towards the node, so v_n > 0 separates. Per node contact, one row:
//
//   node term    nodeTerm(fem_body, node, +1, R_c), R_c = contactFrame(normal)
//   dynamic      + rigidPointTerm(partner's RigidBody, lever, -1, R_c): the partner's twist is
//                  solved with the node's (its b = diag(m, I) times the velocity Bullet integrated
//                  with: gravity and external forces of the step included; less the impulses of
//                  Bullet's rigid contacts that the island solves as rows: rigid_contact_rows.h)
//   link         + rigidPointTerm(the link's LinkBody, lever, -1, R_c): its twist at the
//                  reference point solved with the node's, its effective mass behind it
//   prescribed   (static, kinematic, supported by Bullet's ground, a static link) velocity_offset
//                  = -R_c (v + omega x lever): the partner point's known motion
//
// with mu the pair's coefficient, gap phi0 the contact's gap at the step's start, and k, tau_d
// from RowDefaults. Face contacts: face_contact_rows.h. Anchors are not mapped.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/rigid_partner.h"
#include "torsion/contact/solve/contact_row.h"
#include "torsion/contact/solve/island_body.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap {

/// The rows' contact parameters.
struct RowDefaults {
  /// k, N/m. Near-rigid by default: a node contact should add no compliance of its own to the FEM
  /// body's (whose elasticity is the physics), so k is far above any node's stiffness and SAP's
  /// cap R_n >= beta^2 / (4 pi^2) w decides: the contact's period is the step (beta = 1).
  double stiffness = 1e15;
  /// tau_d as a multiple of dt. 1/pi (Castro et al. 2022, near-rigid regime): the capped contact
  /// oscillator of period beta dt is critically damped when tau_d = beta dt / pi.
  double dissipation_steps = 1.0 / 3.141592653589793;
};

/// What a row against a rigid partner holds whatever its FEM side (one node, or a triangle's
/// nodes): the partner's point term at `lever` when it is an island body (`rigid_body` >= 0),
/// else its point's velocity as the row's offset (static, kinematic); the friction, the defaults'
/// compliance and the gap. `row.frame` must be set.
void completeRigidSide(ContactRow& row, const Eigen::Vector3d& lever, const RigidPartner& partner,
                       int rigid_body, double friction, double gap, const RowDefaults& defaults,
                       double dt);

/// The node contacts' next-step memory: the normal impulse of each solved row, by node and
/// rigid object (N s).
struct LaggedImpulse {
  int node = -1;
  const btCollisionObject* object = nullptr;
  double normal_impulse = 0;
};

/// One FEM body's island: bodies (0: the FEM body; 1.. the dynamic partners), rows, and the
/// correspondence back to the contacts.
struct NodeContactIsland {
  /// Island bodies 1..: RigidBody for a rigid body, LinkBody for a multibody link.
  std::vector<std::unique_ptr<IslandBody>> rigid_bodies;
  std::vector<int> partner_body;  ///< per partner: its island body, or -1 (prescribed)
  std::vector<ContactRow> rows;
  std::vector<int> row_contact;  ///< per row: its index in the NodeContact list, or -1
  /// Per row: its index in the FaceContact list, or -1 (face_contact_rows.h; empty without face
  /// rows).
  std::vector<int> row_face;
  /// Per row: its point in the RigidContactGroup, or -1 (rigid_contact_rows.h; empty without
  /// rigid rows).
  std::vector<int> row_rigid;
  /// Per row: its row in the RigidContactGroup's joint rows, or -1 (rigid_joint_rows.h; empty
  /// without joint rows).
  std::vector<int> row_joint;
};

/// Builds the rows for `contacts` (active or not: every detected node contact, except held nodes
/// against prescribed partners, whose rows have no unknown to act on; an anchor's row is
/// RowKind::kAnchor) of FEM island body `fem_body` against `partners`, with lagged normal
/// impulses from `lagged` (0 for a contact not in it) and parameters `defaults` at step dt.
NodeContactIsland buildNodeContactIsland(const std::vector<NodeContact>& contacts,
                                         const std::vector<RigidPartner>& partners, int fem_body,
                                         const std::vector<LaggedImpulse>& lagged,
                                         const RowDefaults& defaults, double dt);

/// The island's bodies for SapProblem::create: `fem` first, then the rigid bodies.
std::vector<const IslandBody*> islandBodies(const IslandBody& fem, const NodeContactIsland& island);

/// Per partner, the impulse wrench the rows exert on it (N s; force, torque about its centre of
/// mass): sum over its node rows of J^T gamma on its side, -(R_c^T gamma) at the contact's lever
/// (face rows: addFacePartnerImpulses).
std::vector<Vector6d> partnerImpulses(const NodeContactIsland& island,
                                      const std::vector<NodeContact>& contacts,
                                      const std::vector<RigidPartner>& partners,
                                      const SapReport& report);

/// The next step's lagged normal impulses: per node row with gamma_n > 0, its node and object.
std::vector<LaggedImpulse> laggedImpulses(const NodeContactIsland& island,
                                          const std::vector<NodeContact>& contacts,
                                          const std::vector<RigidPartner>& partners,
                                          const SapReport& report);

}  // namespace torsion::sap
