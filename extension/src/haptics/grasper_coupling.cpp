#include "torsion/haptics/grasper_coupling.h"

#include <BulletDynamics/ConstraintSolver/btSliderConstraint.h>
#include <BulletDynamics/Dynamics/btDiscreteDynamicsWorld.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <cmath>

#include "torsion/bt_conversions.h"

namespace torsion::haptics {

namespace {

bool isDynamic(const btRigidBody& body) {
  return !body.isStaticOrKinematicObject() && body.getInvMass() > 0;
}

// m: half the jaw's extent along the palm's x (the jaws are aligned with the palm).
double halfWidthAlongX(const btRigidBody& jaw) {
  btTransform identity;
  identity.setIdentity();
  btVector3 lo, hi;
  jaw.getCollisionShape()->getAabb(identity, lo, hi);
  return 0.5 * toDouble(hi.x() - lo.x());
}

}  // namespace

Status GrasperSettings::validate() const {
  if (!(opening > 0 && std::isfinite(opening))) return Error{"opening must be > 0 (m)"};
  if (!(closing_speed > 0 && std::isfinite(closing_speed)))
    return Error{"closing_speed must be > 0 (m/s)"};
  if (!(grip_force > 0 && std::isfinite(grip_force))) return Error{"grip_force must be > 0 (N)"};
  if (button < 1 || button > 32) return Error{"button must be in [1, 32]"};
  return Ok{};
}

Result<std::unique_ptr<GrasperCoupling>> GrasperCoupling::create(
    const FemSoftBodySolver& solver, btRigidBody& palm, std::array<btRigidBody*, 2> jaws,
    const DeviceMapping& mapping, const ToolCouplingSettings& coupling,
    const GrasperSettings& settings) {
  if (Status ok = settings.validate(); !ok) return ok.error();
  if (solver.world() == nullptr) return Error{"the FEM solver is not attached to a world"};
  btDynamicsWorld& world = *solver.world();
  for (btRigidBody* jaw : jaws) {
    if (jaw == nullptr || !isDynamic(*jaw))
      return Error{"a grasper's jaws must be dynamic rigid bodies (mass > 0)"};
  }
  Result<std::unique_ptr<ToolCoupling>> held =
      ToolCoupling::create(palm, solver, mapping, coupling);
  if (!held) return held.error();
  return std::unique_ptr<GrasperCoupling>(
      new GrasperCoupling(world, std::move(held).value(), jaws, settings));
}

GrasperCoupling::GrasperCoupling(btDynamicsWorld& world, std::unique_ptr<ToolCoupling> palm,
                                 std::array<btRigidBody*, 2> jaws, const GrasperSettings& settings)
    : world_(world), palm_(std::move(palm)), jaws_(jaws), settings_(settings) {
  btRigidBody& body = palm_->tool();
  const btTransform palm_pose = body.getCenterOfMassTransform();
  for (std::size_t i = 0; i < 2; ++i) {
    btRigidBody& jaw = *jaws_[i];
    jaw.setActivationState(DISABLE_DEACTIVATION);
    jaw_half_width_[i] = halfWidthAlongX(jaw);
    palm_->addCarriedMass(1.0 / toDouble(jaw.getInvMass()));
    // The joint's x axis points from the palm's centre plane out to the jaw: its position is 0
    // open and -opening / 2 when the jaw's inner face reaches the centre plane.
    const btTransform in_palm = palm_pose.inverse() * jaw.getCenterOfMassTransform();
    btTransform outward;
    outward.setIdentity();
    if (in_palm.getOrigin().x() < 0) outward.setRotation(btQuaternion(btVector3(0, 0, 1), SIMD_PI));
    btTransform frame_in_palm = outward;
    frame_in_palm.setOrigin(in_palm.getOrigin());
    const btTransform frame_in_jaw = in_palm.inverse() * frame_in_palm;
    joints_[i] = std::make_unique<btSliderConstraint>(body, jaw, frame_in_palm, frame_in_jaw, true);
    btSliderConstraint& joint = *joints_[i];
    joint.setLowerLinLimit(toBtScalar(-0.5 * settings_.opening));
    joint.setUpperLinLimit(0);
    joint.setLowerAngLimit(0);
    joint.setUpperAngLimit(0);
    joint.setPoweredLinMotor(true);
    joint.setMaxLinMotorForce(toBtScalar(settings_.grip_force));
    joint.setTargetLinMotorVelocity(toBtScalar(settings_.closing_speed));  // open
    world_.addConstraint(&joint, true);  // the jaws do not collide with the palm
  }
}

GrasperCoupling::~GrasperCoupling() {
  for (auto& joint : joints_)
    world_.removeConstraint(joint.get());
}

void GrasperCoupling::beforeRigidStep(const device::HandCommand& command, const StepContext& ctx) {
  if (command.tick > 0) closing_ = (command.buttons >> (settings_.button - 1)) & 1u;
  const double velocity = closing_ ? -settings_.closing_speed : settings_.closing_speed;
  for (auto& joint : joints_)
    joint->setTargetLinMotorVelocity(toBtScalar(velocity));
  palm_->beforeRigidStep(command, ctx);
}

double GrasperCoupling::gap() const {
  const btTransform palm_pose = palm_->tool().getCenterOfMassTransform();
  const double x0 = toDouble((palm_pose.inverse() * jaws_[0]->getCenterOfMassPosition()).x());
  const double x1 = toDouble((palm_pose.inverse() * jaws_[1]->getCenterOfMassPosition()).x());
  return std::abs(x1 - x0) - jaw_half_width_[0] - jaw_half_width_[1];
}

}  // namespace torsion::haptics
