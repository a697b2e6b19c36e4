#pragma once
// Bullet's seam: a btSoftBodySolver that steps Torsion's FEM bodies inside a
// btSoftRigidDynamicsWorld. Bullet keeps the broadphase, the soft-rigid collision detection
// (contacts land in btSoftBody::m_rcontacts) and the rigid dynamics; we replace btSoftBody's own
// link solver entirely. Bullet calls, each step (see docs/architecture.md):
//   optimize -> predictMotion -> [collision detection] -> [rigid solve + integrate]
//   -> solveConstraints (our FEM step) -> updateSoftBodies.
// Bullet passes dt as float; we use our own double dt instead.

#include <BulletSoftBody/btSoftBodySolvers.h>

#include <string>
#include <vector>

#include "torsion/bullet/fem_body.h"

namespace torsion {

class FemSoftBodySolver : public btSoftBodySolver {
 public:
  explicit FemSoftBodySolver(double time_step) : time_step_(time_step) {}

  void registerBody(FemBody* body) { bodies_.push_back(body); }
  void unregisterBody(FemBody* body);
  void setTime(double time) { time_ = time; }
  void setTimeStep(double dt) { time_step_ = dt; }

  /// Reports of the last solveConstraints, one per body, in registration order.
  const std::vector<const StepReport*>& lastReports() const { return reports_; }

  // ---- btSoftBodySolver ----
  SolverTypes getSolverType() const override { return CPU_SOLVER; }
  bool checkInitialized() override { return true; }
  void optimize(btAlignedObjectArray<btSoftBody*>& soft_bodies, bool force_update = false) override;
  void copyBackToSoftBodies(bool /*move*/) override {}
  void predictMotion(btScalar solver_dt) override;
  void solveConstraints(btScalar solver_dt) override;
  void updateSoftBodies() override;
  void processCollision(btSoftBody* soft, const btCollisionObjectWrapper* rigid) override;
  void processCollision(btSoftBody* a, btSoftBody* b) override;

 private:
  std::vector<FemBody*> bodies_;
  std::vector<const StepReport*> reports_;
  double time_step_;
  double time_ = 0;
};

}  // namespace torsion
