#pragma once
// RigidBodySpec -> a Bullet rigid body in a FemWorld: the shape, mass and inertia, pose, initial
// velocity, friction and restitution; a kinematic body gets a motion state that Bullet asks for
// the scripted pose at the end of each step (btRigidBody::saveKinematicState), from which Bullet
// derives its velocity, so no caller has to drive it.

#include <BulletDynamics/Dynamics/btRigidBody.h>

#include <array>
#include <memory>
#include <string>

#include "scene_spec.h"
#include "torsion/bullet/fem_world.h"

namespace torsion::scene {

/// A scene rigid body: its name (rigid.csv columns), the live body, for a kinematic one the
/// motion state that scripts it (owned here; the body points to it), for a grasper its jaws
/// (bodies of the world; their joints are the grasper coupling's).
struct SceneRigidBody {
  std::string name;
  btRigidBody* body = nullptr;
  bool kinematic = false;
  std::unique_ptr<btMotionState> script;
  std::array<btRigidBody*, 2> jaws{};
};

/// The collision shape of `spec` (also used by tests/bench to build the same bodies in Bullet's own
/// deformable world).
std::unique_ptr<btCollisionShape> makeRigidShape(const RigidBodySpec& spec);

/// Adds `spec` to `world`. The spec is copied where needed.
SceneRigidBody addSceneRigidBody(FemWorld& world, const RigidBodySpec& spec);

}  // namespace torsion::scene
