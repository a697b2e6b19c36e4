#include "py_rigid.h"

#include "arithmetic_bounds.h"
#include "torsion/bt_conversions.h"
#include "torsion/format_number.h"

namespace torsion::python {

namespace {

std::string who(const char* call, const std::string& name) {
  return std::string(call) + " '" + name + "'";
}

std::string shown(const Eigen::Vector3d& v) {
  return "(" + formatNumber(v.x()) + ", " + formatNumber(v.y()) + ", " + formatNumber(v.z()) + ")";
}

btTransform toTransform(const Frame& frame) {
  return btTransform(toBt(frame.rotation), toBt(frame.origin));
}

// Where a body may be put: as add_rigid_body's frame, within kMaxPlacement of the origin.
Status checkPlacement(const char* call, const std::string& name, const Frame& pose) {
  if (pose.origin.cwiseAbs().maxCoeff() <= scene::kMaxPlacement) return Ok{};
  return Error{who(call, name) + ": position " + shown(pose.origin) +
               " m: each coordinate must be within " + formatNumber(scene::kMaxPlacement) +
               " m of the origin"};
}

// A value Bullet stores as btScalar (float in a float-Bullet build) must stay finite there.
Status checkScalarRange(const char* call, const std::string& name, const char* argument,
                        const Eigen::Vector3d& v, const char* unit) {
  if (toEigen(toBt(v)).allFinite()) return Ok{};
  return Error{who(call, name) + ": " + argument + " " + shown(v) + " " + unit +
               ": beyond the range of Bullet's btScalar"};
}

// Only a dynamic body has velocities and loads of its own: the others follow their targets or
// scripts, or stay put.
Status checkDynamic(PyWorld& world, const char* call, const std::string& name,
                    const btRigidBody& body, const char* what) {
  const RigidKind kind = rigidKind(world, body);
  if (kind == RigidKind::kDynamic) return Ok{};
  const std::string why = kind == RigidKind::kStatic ? "static (mass 0): it does not move"
                          : kind == RigidKind::kScripted
                              ? "kinematic: it follows its scene file's script"
                              : "kinematic: it follows its targets (set_kinematic_target)";
  return Error{who(call, name) + ": the body is " + why + "; only a dynamic body (mass > 0) " +
               what};
}

}  // namespace

RigidKind rigidKind(PyWorld& world, const btRigidBody& body) {
  if (const scene::SceneRigidBody* scene_body = world.sceneRigidBody(body);
      scene_body != nullptr && scene_body->script) {
    return RigidKind::kScripted;
  }
  if (body.isKinematicObject()) return RigidKind::kKinematic;
  if (body.isStaticObject()) return RigidKind::kStatic;
  return RigidKind::kDynamic;
}

const char* rigidKindName(RigidKind kind) {
  switch (kind) {
    case RigidKind::kDynamic:
      return "dynamic";
    case RigidKind::kStatic:
      return "static";
    case RigidKind::kKinematic:
    case RigidKind::kScripted:
      return "kinematic";
  }
  return "static";
}

Status setRigidPose(PyWorld& world, const std::string& name, btRigidBody& body, const Frame& pose) {
  const char* call = "set_pose";
  if (rigidKind(world, body) == RigidKind::kScripted) {
    return Error{who(call, name) +
                 ": the body is kinematic and follows its scene file's script, "
                 "which sets its pose at every step"};
  }
  if (Status placed = checkPlacement(call, name, pose); !placed) return placed;
  const btTransform transform = toTransform(pose);
  body.setWorldTransform(transform);
  body.setInterpolationWorldTransform(transform);
  if (btMotionState* motion = body.getMotionState()) motion->setWorldTransform(transform);
  if (world.kinematicTarget(body) != nullptr) world.setKinematicTarget(body, transform);
  world.world().bulletWorld().updateSingleAabb(&body);
  body.activate(true);
  return Ok{};
}

Status setRigidVelocity(PyWorld& world, const std::string& name, btRigidBody& body,
                        const std::optional<Eigen::Vector3d>& linear,
                        const std::optional<Eigen::Vector3d>& angular) {
  const char* call = "set_velocity";
  if (Status dynamic = checkDynamic(world, call, name, body, "has a velocity to set"); !dynamic)
    return dynamic;
  if (linear && !(linear->stableNorm() <= scene::kMaxInitialSpeed)) {
    return Error{who(call, name) + ": linear " + shown(*linear) +
                 " m/s: the speed must be at most " + formatNumber(scene::kMaxInitialSpeed) +
                 " m/s"};
  }
  if (angular && !(angular->stableNorm() <= scene::kMaxInitialSpin)) {
    return Error{who(call, name) + ": angular " + shown(*angular) +
                 " rad/s: the spin must be at most " + formatNumber(scene::kMaxInitialSpin) +
                 " rad/s"};
  }
  if (linear) {
    body.setLinearVelocity(toBt(*linear));
    body.setInterpolationLinearVelocity(toBt(*linear));
  }
  if (angular) {
    body.setAngularVelocity(toBt(*angular));
    body.setInterpolationAngularVelocity(toBt(*angular));
  }
  body.activate(true);
  return Ok{};
}

Status applyRigidLoad(PyWorld& world, const char* call, const std::string& name, btRigidBody& body,
                      const Eigen::Vector3d& force, const std::optional<Eigen::Vector3d>& point,
                      const Eigen::Vector3d& torque) {
  if (Status dynamic = checkDynamic(world, call, name, body, "takes forces"); !dynamic)
    return dynamic;
  if (Status s = checkScalarRange(call, name, "force", force, "N"); !s) return s;
  if (Status s = checkScalarRange(call, name, "torque", torque, "N m"); !s) return s;
  Wrench load{force, torque};
  if (point) {
    // About the centre of mass, where Bullet's accumulators take torques.
    const Eigen::Vector3d arm = *point - toEigen(body.getCenterOfMassPosition());
    load.torque += arm.cross(force);
    if (Status s = checkScalarRange(call, name, "torque of the force about the centre of mass",
                                    load.torque, "N m");
        !s) {
      return s;
    }
  }
  world.queueLoad(body, load);
  return Ok{};
}

Status setKinematicTarget(PyWorld& world, const std::string& name, btRigidBody& body,
                          const Frame& target) {
  const char* call = "set_kinematic_target";
  const RigidKind kind = rigidKind(world, body);
  if (kind == RigidKind::kDynamic) {
    return Error{who(call, name) + ": the body is dynamic (mass " +
                 formatNumber(1 / toDouble(body.getInvMass())) +
                 " kg); only a body of mass 0 can be kinematic (add it with mass=0)"};
  }
  if (kind == RigidKind::kScripted) {
    return Error{who(call, name) + ": the body follows its scene file's kinematic script"};
  }
  if (Status placed = checkPlacement(call, name, target); !placed) return placed;
  if (kind == RigidKind::kStatic) {
    // Bullet's recipe for a kinematic body: mass 0 plus CF_KINEMATIC_OBJECT, never asleep. Bullet
    // reads its pose from the motion state before each step and derives its velocity.
    body.setCollisionFlags(body.getCollisionFlags() | btCollisionObject::CF_KINEMATIC_OBJECT);
    body.setActivationState(DISABLE_DEACTIVATION);
  }
  world.setKinematicTarget(body, toTransform(target));
  return Ok{};
}

}  // namespace torsion::python
