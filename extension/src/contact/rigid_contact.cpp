// The FEM-rigid contact step (docs/contact-pipeline.md, "Pipeline, per step"): candidates from
// Bullet's broadphase, the narrow phase (rigid_contact_detection.cpp), the rows of the body's
// island and its answer (rigid_contact_convex.cpp), and the rigid bodies' new velocities. detect
// reads as the list of its stages.

#include "torsion/contact/rigid_contact.h"

#include <LinearMath/btTransformUtil.h>

#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/contact/solve/rigid_contact_rows.h"
#include "torsion/contact/solve/rigid_joint_rows.h"

namespace torsion {

RigidContactSolver::RigidContactSolver(std::shared_ptr<const FemModel> model, btSoftBody* soft_body)
    : model_(std::move(model)), soft_body_(soft_body), faces_(model_->mesh()) {
  const int n = model_->nodeCount();
  surface_.assign(static_cast<size_t>(n), 0);
  for (const Triangle& tri : model_->mesh().surfaceTriangles()) {
    for (int a = 0; a < 3; ++a)
      surface_[static_cast<size_t>(tri[static_cast<size_t>(a)])] = 1;
  }
  node_contact_.assign(static_cast<size_t>(n), -1);
}

void RigidContactSolver::beginStep(double /*dt*/) {
  candidates_.clear();
  links_.beginStep();
  recordAnchorStartPoses();
}

void RigidContactSolver::addCandidate(const btCollisionObject* object) {
  // A concave object reaches us once per overlapping triangle: keep it once.
  if (std::find(candidates_.begin(), candidates_.end(), object) == candidates_.end())
    candidates_.push_back(object);
  links_.recordStartPose(object);
}

bool RigidContactSolver::detect(const FemState& state, const NodeConstraints& constraints,
                                double dt, sap::JointLedger* joints) {
  joints_ = joints;
  rememberActiveContacts();
  forgetLastStep(dt);
  if (candidates_.empty() && anchors_.empty()) return false;
  findContacts(state, constraints, dt);
  addAnchorContacts(state, constraints);
  dropUntouchedPartners();
  takeRigidContacts();
  recordDetectionStats();
  return !contacts_.empty() || !faces_.empty();
}

void RigidContactSolver::finish() {
  // The island's rigid impulses onto Bullet's points, which now carry them (rigid_contact_rows.h).
  sap::writeBackRigidImpulses(rigid_group_, rigid_impulses_);
  if (joints_ != nullptr) sap::writeBackJointImpulses(rigid_group_, joint_impulses_, *joints_, dt_);
  rigid_group_ = {};
  rigid_impulses_.clear();
  joint_impulses_.clear();
  joints_ = nullptr;
  links_.applyImpulses(partners_, dt_);
  for (RigidPartner& k : partners_) {
    if (k.link != nullptr) continue;
    if (k.supported && k.body != nullptr) {
      // Explicit: the impulse changes the velocity only; Bullet's rigid solver meets it next
      // step together with the body's other contacts (the ground), which alone it knows.
      k.body->applyCentralImpulse(toBt(k.impulse.head<3>()));
      k.body->applyTorqueImpulse(toBt(k.impulse.tail<3>()));
      k.body->activate();
      continue;
    }
    if (!k.dynamic || k.body == nullptr || k.applied_by_another_body) continue;
    if (k.velocity == k.entry_velocity) continue;
    // Bullet integrated the pose with entry_velocity; the step's velocity is `velocity`
    // (symplectic Euler with the contact impulse inside the step).
    const Vector6d dV = k.velocity - k.entry_velocity;
    btTransform corrected;
    btTransformUtil::integrateTransform(k.body->getCenterOfMassTransform(), toBt(dV.head<3>()),
                                        toBt(dV.tail<3>()), toBtScalar(dt_), corrected);
    k.body->setLinearVelocity(toBt(k.velocity.head<3>()));
    k.body->setAngularVelocity(toBt(k.velocity.tail<3>()));
    k.body->setCenterOfMassTransform(corrected);
    if (k.body->getMotionState() != nullptr) k.body->getMotionState()->setWorldTransform(corrected);
    k.body->activate();
  }
}

}  // namespace torsion
