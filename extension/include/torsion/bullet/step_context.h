#pragma once
// What one FEM step needs to know about the world's clock, handed down the step instead of being
// copied into every object that steps (the body, its stepper, its contacts, its hands).
//
// Bullet owns the clock: every internal substep of btDiscreteDynamicsWorld::stepSimulation
// (dt, maxSubSteps, fixedTimeStep) is one FEM step of that substep's length, and the FEM time is
// the sum of the substeps taken since the solver joined the world (FemSoftBodySolver).

#include <Eigen/Core>
#include <cstdint>

namespace torsion {

namespace sap {
class JointLedger;
}  // namespace sap

struct StepContext {
  double time = 0;         ///< s, the step goes from `time` to `time + dt`
  double dt = 0;           ///< s, this substep's length, as Bullet passed it
  std::int64_t index = 0;  ///< 1-based index of this step among the solver's FEM steps
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();  ///< m/s^2, the world's gravity this step
  /// The world's joints (btTypedConstraint) this substep and what Bullet's solver did with them
  /// (contact/solve/joint_ledger.h): the convex contact solve takes the joints of the rigid bodies
  /// it takes. Owned by FemSoftBodySolver; null when the step has no world.
  sap::JointLedger* joints = nullptr;

  double endTime() const { return time + dt; }
};

}  // namespace torsion
