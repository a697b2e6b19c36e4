#pragma once
// Steering a PyWorld's rigid bodies between steps, as PyBullet and MuJoCo programs do: moving a
// body at once (pose, velocity), a force and torque for the next step, and a kinematic target
// (MuJoCo's mocap bodies). Python-free: the bindings (bind_parts.cpp) turn the arguments into
// numbers (types, shapes, finiteness); these check the values against the scene file's bounds
// and the body's kind, and change nothing when they return an error. Every error message starts
// with the call and the body: "set_velocity 'slab': ...".

#include <btBulletDynamicsCommon.h>

#include <optional>
#include <string>

#include "py_world.h"
#include "torsion/constraints/frame.h"
#include "torsion/result.h"

namespace torsion::python {

/// How a rigid body moves: by Bullet's dynamics (mass > 0), not at all (mass 0), following the
/// targets Python sets (a static body given a kinematic target), or following its scene file's
/// "kinematic" script.
enum class RigidKind { kDynamic, kStatic, kKinematic, kScripted };

RigidKind rigidKind(PyWorld& world, const btRigidBody& body);
/// "dynamic", "static" or "kinematic" (scripted or not).
const char* rigidKindName(RigidKind kind);

/// Moves the body's centre of mass frame to `pose` now, keeping its velocities, and wakes it; a
/// kinematic body's target moves with it (it stays there). Errors: a scripted body; a position
/// beyond scene::kMaxPlacement of the origin.
Status setRigidPose(PyWorld& world, const std::string& name, btRigidBody& body, const Frame& pose);

/// Sets the linear (m/s) and angular (rad/s, world axes) velocity of a dynamic body now; an
/// absent one is kept. Errors: a body that is not dynamic; a speed above
/// scene::kMaxInitialSpeed or a spin above scene::kMaxInitialSpin.
Status setRigidVelocity(PyWorld& world, const std::string& name, btRigidBody& body,
                        const std::optional<Eigen::Vector3d>& linear,
                        const std::optional<Eigen::Vector3d>& angular);

/// Adds `force` (N) acting at `point` (m, world; the centre of mass when absent) and `torque`
/// (N m, world axes) to the load of a dynamic body for the next step only. Errors: a body that
/// is not dynamic; a value that Bullet's btScalar cannot hold. `call` (apply_force or
/// apply_torque) starts the messages.
Status applyRigidLoad(PyWorld& world, const char* call, const std::string& name, btRigidBody& body,
                      const Eigen::Vector3d& force, const std::optional<Eigen::Vector3d>& point,
                      const Eigen::Vector3d& torque);

/// The body moves to `target` during the next step, at the velocity that takes it there in dt,
/// and stays there until the next target; a static body becomes kinematic at its first target.
/// Errors: a dynamic or scripted body; a position beyond scene::kMaxPlacement.
Status setKinematicTarget(PyWorld& world, const std::string& name, btRigidBody& body,
                          const Frame& target);

}  // namespace torsion::python
