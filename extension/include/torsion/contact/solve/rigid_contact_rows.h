#pragma once
// Contacts between rigid bodies as SAP rows (docs/contact-solve.md, "Rigid contacts in the
// island"): the dynamic rigid bodies a FEM body's island solves, with the contacts Bullet found
// between them and around them, so that a box resting on a soft slab and carrying another is
// solved once, with everything that touches it, instead of by Bullet's rigid solver and then by
// the FEM's, one after the other.
//
// Bullet steps its rigid bodies (contacts and joints included) before the FEM step. For a body the
// island takes over, the FEM step undoes Bullet's contact impulses: its momentum before contact is
//
//     M v_free = M v_bullet - w_bullet,   w_bullet = sum over its contact points of J^T lambda
//
// lambda the impulses Bullet's solver left on the manifold points (m_appliedImpulse along
// m_normalWorldOnB, m_appliedImpulseLateral1/2 along m_lateralFrictionDir1/2), and every contact
// point becomes a row. When the step ends (RigidContactSolver::finish, with the bodies' new
// velocities) the island's impulses are written back onto the points (the normal on
// m_appliedImpulse, the friction on m_lateralFrictionDir1 with m_appliedImpulseLateral2 zero), so
// the points always hold the impulses that the bodies' velocities carry: a second FEM body
// touching the same group in the same step undoes the first's rigid impulses exactly, and
// Bullet's next solve warm-starts from the island's answer. The group is gathered once per step
// (at detection) and its pointers into Bullet's manifolds are dropped when the step ends. Its
// bodies' joint impulses are undone likewise (joint_ledger.h) and their joints solved as rows
// (rigid_joint_rows.h).
//
// A group is the dynamic rigid bodies connected by contact or by joint to the seeds (the island's
// rigid partners), through dynamic rigid bodies; static and kinematic objects end it. Its joints
// become rows too (rigid_joint_rows.h). A group is taken
// only when Bullet's step can be undone exactly; otherwise Bullet keeps it (the explicit
// coupling), and the reason is reported:
//   - a body touching a multibody link: Featherstone's solver owns that contact;
//   - a body asleep (Bullet did not solve it this step), or with linear or angular factors other
//     than 1 (Bullet's solver scales its response);
//   - a contact with rolling or spinning friction (Bullet does not record those impulses).
//
// Per contact point, one row. Bullet's normal points from its body B to its body A, so A is the
// row's side B (pushed along +n) and B its side A:
//
//   A dynamic    rigidPointTerm(A's body, p_A - c_A, +1, R_c),  p_A the point on A
//   B dynamic    rigidPointTerm(B's body, p_B - c_B, -1, R_c)
//   prescribed   its point's velocity in velocity_offset (+R_c v_A for A, -R_c v_B for B)
//
// with R_c = contactFrame(n), gap the point's distance (negative in penetration), mu Bullet's
// combined friction, k and tau_d from RowDefaults (near-rigid, as a node against a rigid body),
// and the lagged normal impulse Bullet's own solve gave the point this step. Restitution is not
// modelled (Bullet's combined restitution is ignored): the island's contacts are inelastic.

#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <BulletDynamics/ConstraintSolver/btTypedConstraint.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "torsion/contact/solve/rigid_contact_group.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap {

struct NodeContactIsland;  // node_contact_rows.h
struct RowDefaults;

/// The step's start pose of a collision object (RigidContactSolver::startPoseOf).
using StartPose = std::function<btTransform(const btCollisionObject&)>;

/// The groups of `seeds` (dynamic rigid bodies) that can be taken, merged: every dynamic body
/// reached from a seed through Bullet's contact points (those Bullet's solver used: distance
/// within the manifold's processing threshold, both objects responding) or through `joints` (the
/// world's enabled joints), and those points. A component that cannot be taken (above) is left
/// out whole, its reason in kept_by_bullet. The joints' rows: rigid_joint_rows.h.
RigidContactGroup gatherRigidContactGroup(btDispatcher& dispatcher,
                                          const std::vector<btRigidBody*>& seeds,
                                          const StartPose& start_pose,
                                          const std::vector<btTypedConstraint*>& joints);

/// Appends one row per point of `group` to `island`, `group_body[i]` the island body of the
/// group's body i; island.row_rigid holds each row's point index (-1 for the rows before).
void addRigidContactRows(NodeContactIsland& island, const RigidContactGroup& group,
                         const std::vector<int>& group_body, const RowDefaults& defaults,
                         double dt);

/// Per point of the group, the island's impulse on Bullet's body A (N s, world), from the rigid
/// rows of `island` and its solve's `report`.
std::vector<Eigen::Vector3d> rigidPointImpulses(const NodeContactIsland& island,
                                                const RigidContactGroup& group,
                                                const SapReport& report);

/// Writes `impulses` (rigidPointImpulses) back onto Bullet's points (above).
void writeBackRigidImpulses(const RigidContactGroup& group,
                            const std::vector<Eigen::Vector3d>& impulses);

}  // namespace torsion::sap
