#pragma once
// A ready-made Bullet world with FEM bodies beside rigid bodies, for programs that do not have a
// world of their own:
//
//   FemWorld world(settings);
//   FemBody* cyl = world.addBody("cyl", mesh, material).value();
//   world.addRigidBody(std::make_unique<btBoxShape>(...), 1.0, transform);
//   while (...) { WorldStepReport r = world.step(); if (!r.ok) ... }
//
// A thin convenience over exactly the path a user's own world takes (fem_soft_body_solver.h):
// it builds a btSoftRigidDynamicsWorld with a FemSoftBodySolver, attaches it, and step() is
// stepSimulation(dt, 0), one FEM step of settings.solver.time_step. The clock is the solver's.
//
// The world owns every Bullet object and FEM body it creates; pointers it returns stay valid for
// its lifetime. Single-threaded API: call it from the simulation thread only (the solver's own
// worker threads are internal).

#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <string>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/constraints/frame.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/solve/parallel.h"
#include "torsion/solve/solver_settings.h"

namespace torsion {

struct WorldSettings {
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.81);  ///< m/s^2, for FEM and rigid bodies
  SolverSettings solver;

  Status validate() const;
};

struct WorldStepReport {
  bool ok = true;       ///< false when a body's step failed fatally; the world must not go on
  int step = 0;         ///< index of the step just taken (1-based)
  std::string message;  ///< "body 'cyl', step 123: blow-up: ..." when not ok
};

/// A FemWorld at a moment: the FEM solver's checkpoint and the world's rigid bodies.
struct WorldCheckpoint {
  struct RigidState {
    btTransform pose;
    btVector3 linear_velocity, angular_velocity;
  };
  FemCheckpoint fem;
  std::vector<RigidState> rigid;  ///< in rigidBodies() order
};

class FemWorld {
 public:
  explicit FemWorld(const WorldSettings& settings);
  ~FemWorld();
  FemWorld(const FemWorld&) = delete;
  FemWorld& operator=(const FemWorld&) = delete;

  /// Adds an FEM body whose rest shape is `mesh` (linear tets) placed at `pose`, discretised with
  /// `element` (tet10: a mid-edge node on every edge, see mesh/quadratic_tet_mesh.h). Errors: bad
  /// material, a duplicate name.
  ///
  /// `numbering` kCacheFriendly renumbers the mesh when that pays (mesh/input_numbering.h): the
  /// body's node and tet numbers then differ from the mesh's, and FemBody::inputNumbering()
  /// maps them (scene files and Python do so by default, and translate what they show).
  Result<FemBody*> addBody(const std::string& name, const TetMesh& mesh, const Material& material,
                           const Frame& pose = {}, ElementKind element = ElementKind::kTet4,
                           NodeNumbering numbering = NodeNumbering::kAsGiven);
  /// Adds a rigid body (mass 0: static). The world owns the shape and the body.
  btRigidBody* addRigidBody(std::unique_ptr<btCollisionShape> shape, double mass,
                            const btTransform& transform);

  /// Tracks a rigid body that someone else created and added to bulletWorld() (e.g. Bullet's
  /// btBulletWorldImporter): it is listed in rigidBodies() (drawing, checkpoints) but neither
  /// removed from the world nor deleted by this FemWorld; its owner must keep it alive as long.
  void trackRigidBody(btRigidBody* body);
  /// Takes a rigid body of rigidBodies() out of the world for good: out of Bullet's world, out of
  /// every FEM body's contact memory (FemBody::forgetObject) and out of rigidBodies() (the others
  /// keep their order); one the world owns is deleted with its shape and motion state, a tracked
  /// one is left to its owner. Pointers to it are stale afterwards, and checkpoints taken before
  /// no longer restore (restore() counts the rigid bodies). Errors, changing nothing: not a rigid
  /// body of this world; an FEM body anchors nodes to it (remove the anchors first); a Bullet
  /// constraint refers to it (remove it from bulletWorld() first).
  Status removeRigidBody(btRigidBody* body);

  /// One step of settings().solver.time_step (also with no bodies: the clock moves on). Not ok
  /// when a rigid body became non-finite or overflowed (bullet/rigid_health.h) or an FEM step
  /// failed. A failed FEM step is not undone (that would cost every step a checkpoint): the
  /// bodies before the failing one in bodies() took the step; the failing one's state() holds
  /// what its step computed (often non-finite: that is how the failure was found) while its
  /// btSoftBody keeps the last good step; those after it did not step; the rigid bodies took the
  /// step and the clock counts it. From then on step() moves nothing and reports the same
  /// failure. To go back, restore() a checkpoint taken before the failed step (it clears the
  /// failure too).
  WorldStepReport step();

  /// Live edit between steps (the viewer's dt and solver keys): the next steps use `solver`
  /// (time step, linear solver, preconditioner, tolerance, caps); time and state go on. Errors,
  /// leaving the settings as they were: invalid settings, or a different thread count (the
  /// worker pool is made once per world).
  Status setSolverSettings(const SolverSettings& solver);
  /// Live edit between steps: the next steps pull the FEM bodies and every dynamic rigid body of
  /// bulletWorld() with `gravity` (m/s^2), also bodies asleep (they are woken) and bodies added
  /// later; a body flagged BT_DISABLE_WORLD_GRAVITY keeps its own. Errors, changing nothing: not
  /// finite.
  Status setGravity(const Eigen::Vector3d& gravity);

  /// Everything the next steps read: FEM bodies (their warm starts and node groups), the clock,
  /// the rigid bodies' poses and velocities. Not in it: hands (Hand::checkpoint) and Bullet's
  /// contact caches between rigid bodies (their persistent manifolds), which Bullet rebuilds.
  WorldCheckpoint checkpoint();
  /// Back to `checkpoint`. Errors, changing nothing: bodies removed or rigid bodies added since.
  Status restore(const WorldCheckpoint& checkpoint);

  double time() const;
  int stepCount() const;
  const WorldSettings& settings() const { return settings_; }
  const std::vector<std::unique_ptr<FemBody>>& bodies() const;
  FemBody* body(const std::string& name) const;
  const std::vector<btRigidBody*>& rigidBodies() const { return rigid_bodies_; }
  btSoftRigidDynamicsWorld& bulletWorld() { return *world_; }
  FemSoftBodySolver& femSolver() { return *soft_solver_; }
  const FemSoftBodySolver& femSolver() const { return *soft_solver_; }

 private:
  WorldSettings settings_;
  std::unique_ptr<btCollisionConfiguration> collision_configuration_;
  std::unique_ptr<btCollisionDispatcher> dispatcher_;
  std::unique_ptr<btBroadphaseInterface> broadphase_;
  std::unique_ptr<btSequentialImpulseConstraintSolver> constraint_solver_;
  std::unique_ptr<FemSoftBodySolver> soft_solver_;
  std::unique_ptr<btSoftRigidDynamicsWorld> world_;  // destroyed before soft_solver_
  std::vector<std::unique_ptr<btCollisionShape>> shapes_;
  std::vector<std::unique_ptr<btMotionState>> motion_states_;
  std::vector<btRigidBody*> rigid_bodies_;  // owned ones deleted after removal from the world
  std::vector<btRigidBody*> tracked_;       // not owned (trackRigidBody)
  std::vector<btRigidBody*> owned_;  // addRigidBody's, each with shapes_[k], motion_states_[k]
};

}  // namespace torsion
