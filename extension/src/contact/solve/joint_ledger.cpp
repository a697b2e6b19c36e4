#include "torsion/contact/solve/joint_ledger.h"

#include "torsion/bt_conversions.h"

namespace torsion::sap {

namespace {

bool isDynamic(const btRigidBody& body) {
  return !body.isStaticOrKinematicObject() && body.getInvMass() > 0;
}

// The angular velocity change Bullet's solver gives `body` for its gyroscopic torque this step
// (btSequentialImpulseConstraintSolver::convertBodies, by the body's flags).
btVector3 gyroscopicChange(const btRigidBody& body, const btContactSolverInfo& info, btScalar dt) {
  btVector3 change(0, 0, 0);
  const int flags = body.getFlags();
  if (flags & BT_ENABLE_GYROSCOPIC_FORCE_EXPLICIT)
    change -= body.computeGyroscopicForceExplicit(info.m_maxGyroscopicForce) *
              body.getInvInertiaTensorWorld() * dt;
  if (flags & BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_WORLD)
    change += body.computeGyroscopicImpulseImplicit_World(dt);
  if (flags & BT_ENABLE_GYROSCOPIC_FORCE_IMPLICIT_BODY)
    change += body.computeGyroscopicImpulseImplicit_Body(dt);
  return change;
}

std::vector<btTypedConstraint*> enabledJoints(btDynamicsWorld& world) {
  std::vector<btTypedConstraint*> joints;
  for (int c = 0; c < world.getNumConstraints(); ++c) {
    btTypedConstraint* joint = world.getConstraint(c);
    if (joint->isEnabled()) joints.push_back(joint);
  }
  return joints;
}

}  // namespace

void JointLedger::begin(btDynamicsWorld& world, double dt) {
  joints_ = enabledJoints(world);
  bodies_.clear();
  const btContactSolverInfo& info = world.getSolverInfo();
  erp_ = static_cast<double>(info.m_erp);
  global_cfm_ = static_cast<double>(info.m_globalCfm);
  damping_ = static_cast<double>(info.m_damping);
  for (btTypedConstraint* joint : joints_) {
    for (const btRigidBody* body : {&joint->getRigidBodyA(), &joint->getRigidBodyB()}) {
      if (!isDynamic(*body) || bodies_.count(body) > 0) continue;
      const btVector3 omega =
          body->getAngularVelocity() + gyroscopicChange(*body, info, static_cast<btScalar>(dt));
      bodies_[body].start_twist =
          (Vector6d() << toEigen(body->getLinearVelocity()), toEigen(omega)).finished();
    }
  }
}

void JointLedger::refresh(btDynamicsWorld& world) {
  joints_ = enabledJoints(world);
}

std::optional<Vector6d> JointLedger::startTwist(const btRigidBody& body) const {
  const auto found = bodies_.find(&body);
  if (found == bodies_.end()) return std::nullopt;
  return found->second.start_twist;
}

Vector6d JointLedger::jointImpulse(const btRigidBody& body, const Vector6d& contact_impulse,
                                   const Matrix6d& mass_matrix, double dt) const {
  const auto found = bodies_.find(&body);
  if (found == bodies_.end()) return Vector6d::Zero();
  const Entry& e = found->second;
  if (e.island_impulse) return *e.island_impulse;
  if (!e.start_twist) return Vector6d::Zero();
  const Vector6d now =
      (Vector6d() << toEigen(body.getLinearVelocity()), toEigen(body.getAngularVelocity()))
          .finished();
  const Vector6d forces =
      (Vector6d() << toEigen(body.getTotalForce()), toEigen(body.getTotalTorque())).finished();
  return mass_matrix * (now - *e.start_twist) - dt * forces - contact_impulse;
}

void JointLedger::setIslandImpulse(const btRigidBody& body, const Vector6d& impulse) {
  bodies_[&body].island_impulse = impulse;
}

}  // namespace torsion::sap
