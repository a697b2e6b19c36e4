#include "torsion/bullet/fem_soft_body_solver.h"

#include <algorithm>

namespace torsion {

void FemSoftBodySolver::unregisterBody(FemBody* body) {
  bodies_.erase(std::remove(bodies_.begin(), bodies_.end(), body), bodies_.end());
}

void FemSoftBodySolver::optimize(btAlignedObjectArray<btSoftBody*>& /*soft_bodies*/,
                                 bool /*force_update*/) {
  // Our bodies register themselves through FemWorld; nothing to rebuild per step.
}

void FemSoftBodySolver::predictMotion(btScalar /*solver_dt*/) {
  for (FemBody* body : bodies_)
    body->predict(time_step_);
}

void FemSoftBodySolver::solveConstraints(btScalar /*solver_dt*/) {
  reports_.clear();
  for (FemBody* body : bodies_)
    reports_.push_back(&body->advance(time_, time_step_));
}

void FemSoftBodySolver::updateSoftBodies() {
  for (FemBody* body : bodies_) {
    body->softBody()->updateNormals();
    body->softBody()->updateBounds();
  }
}

void FemSoftBodySolver::processCollision(btSoftBody* soft, const btCollisionObjectWrapper* rigid) {
  // A broadphase pair: our narrow phase runs in FemBody::advance, at the rigid body's pose after
  // Bullet's rigid integration (docs/contact.md). Bullet's own CollideSDF_RS is not used.
  for (FemBody* body : bodies_) {
    if (body->softBody() == soft) body->contacts().addCandidate(rigid->getCollisionObject());
  }
}

void FemSoftBodySolver::processCollision(btSoftBody* a, btSoftBody* b) {
  a->defaultCollisionHandler(b);
}

}  // namespace torsion
