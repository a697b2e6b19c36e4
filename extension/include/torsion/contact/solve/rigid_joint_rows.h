#pragma once
// Bullet's joints as SAP rows (docs/contact-solve.md, "Joints in the island"): a rigid body that an
// island takes from Bullet (rigid_contact_rows.h) is solved with its joints too, so that a bob on
// a hinge carrying a FEM bar, or a box pushed by a jointed arm, is solved once with everything
// that acts on it, instead of by Bullet's rigid solver and then by the FEM's.
//
// Each row of each joint (btTypedConstraint) with a body in the group is asked of the joint as
// Bullet's own solver asks it (btSequentialImpulseConstraintSolver::convertJoint: getInfo1, then
// getInfo2 with fps = 1/dt and the world's erp, cfm and damping), with the bodies put back at
// their step-start poses and twists for the call: Bullet's solve saw them there. A row is
//
//     jacobian_a . twist_a + jacobian_b . twist_b -> target,  lambda in [lower, upper]
//
// (bounds clamped to the joint's breaking threshold), which sap_problem.h solves as a joint row
// with Bullet's target and bounds and the near-rigid compliance (or Bullet's cfm where larger).
//
// Bullet's joint impulses are undone through the JointLedger (joint_ledger.h). When the step ends
// (RigidContactSolver::finish) each joint gets what Bullet's solver would have left on it: its
// btJointFeedback forces (impulse / dt), its applied impulse (its last row's, as Bullet) and, when
// a row's impulse reaches the breaking threshold, it is disabled; the ledger gets each body's
// joint impulse.

#include <vector>

#include "torsion/contact/solve/joint_ledger.h"
#include "torsion/contact/solve/rigid_contact_group.h"
#include "torsion/contact/solve/rigid_contact_rows.h"

namespace torsion::sap {

/// Adds to `group` the joints of `ledger` with a body in the group, and their rows at the step's
/// start (`start_pose`; each dynamic body's twist from the ledger).
void addJointRows(RigidContactGroup& group, const JointLedger& ledger, const StartPose& start_pose,
                  double dt);

/// Appends one SAP row per joint row of `group` to `island` (`group_body[i]`: the island body of
/// the group's body i); island.row_joint holds each row's index in group.joint_rows.
void addRigidJointRows(NodeContactIsland& island, const RigidContactGroup& group,
                       const std::vector<int>& group_body);

/// Per joint row of the group, its impulse lambda in the island's solve.
std::vector<double> jointRowImpulses(const NodeContactIsland& island,
                                     const RigidContactGroup& group, const SapReport& report);

/// The joints' impulses `lambda` (jointRowImpulses) onto Bullet's joints and into `ledger`
/// (above).
void writeBackJointImpulses(const RigidContactGroup& group, const std::vector<double>& lambda,
                            JointLedger& ledger, double dt);

}  // namespace torsion::sap
