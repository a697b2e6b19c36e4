#pragma once
// Bullet's seam: Torsion's btSoftBodySolver. A user's btSoftRigidDynamicsWorld or
// btSoftMultiBodyDynamicsWorld takes it at construction (Bullet accepts its soft-body solver only
// there), torsion::attach() binds it to that world, and from then on the world steps Torsion's FEM
// bodies with its own clock:
//
//   torsion::FemSoftBodySolver fem;
//   btSoftRigidDynamicsWorld world(&dispatcher, &broadphase, &solver, &config, &fem);
//   torsion::attach(world).value();                      // or keep the returned pointer
//   torsion::FemBody* cyl = fem.addBody("cyl", mesh, material).value();
//   world.stepSimulation(1 / 60., 10, 1 / 240.);         // four FEM steps of 1/240 s
//   if (!fem.status().ok) { /* fem.status().message */ }
//
// Each internal substep of stepSimulation is one FEM step of that substep's length; the FEM time
// is the sum of the substeps since the solver was bound (docs/bullet-integration.md). Bullet
// calls, each substep:
//   optimize -> predictMotion -> [collision detection: processCollision per broadphase pair]
//   -> [rigid solve + integrate] -> solveConstraints (the FEM step) -> updateSoftBodies.
//
// Bullet's own soft bodies (cloth, ropes, btSoftBodyHelpers volumes) in the same world are handed
// to Bullet's default solver, so they move and collide with rigid bodies as without Torsion.
// FEM bodies touch rigid bodies and multibody links (contact/rigid_contact.h) and each other
// (bullet/fem_contact_islands.h: on by default, setFemContact), but not Bullet's soft bodies: when
// such a pair touches, the solver says so (UnsupportedContact), as it does for two FEM bodies
// while contact between them is off.
//
// Simulation thread only. The solver must be constructed before the world that uses it and
// destroyed after it (Bullet keeps a pointer to it and to the bodies' btSoftBody objects until the
// world is gone); it owns its FEM bodies.

#include <BulletSoftBody/btDefaultSoftBodySolver.h>
#include <BulletSoftBody/btSoftBodySolvers.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_contact_islands.h"
#include "torsion/bullet/step_context.h"
#include "torsion/constraints/frame.h"
#include "torsion/contact/solve/joint_ledger.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"
#include "torsion/solve/parallel.h"
#include "torsion/solve/solver_settings.h"

class btDiscreteDynamicsWorld;
class btSoftRigidDynamicsWorld;
class btSoftMultiBodyDynamicsWorld;

namespace torsion {

class SoftBodyTouch;

/// Told before and after every FEM step, on the simulation thread, inside stepSimulation (hands
/// driven by devices use it: haptics/haptic_runtime.h).
class StepListener {
 public:
  virtual ~StepListener() = default;
  /// Before Bullet's rigid solve of the substep (predictMotion), while the solver is healthy;
  /// afterFemStep follows in the same substep. `ctx.joints` is null here.
  virtual void beforeRigidStep(const StepContext& /*ctx*/) {}
  virtual void beforeFemStep(const StepContext& /*ctx*/) {}
  /// `ok`: every FEM body's step succeeded.
  virtual void afterFemStep(const StepContext& /*ctx*/, bool /*ok*/) {}
};

/// The solver's health: ok until a step fails fatally, then the first failure, kept (the FEM
/// bodies stop where they were; Bullet's rigid and soft bodies go on).
struct FemSolverStatus {
  bool ok = true;
  std::int64_t failed_step = 0;  ///< index of the failed step, 0 while ok
  /// "body 'cyl', step 123: blow-up: ...", or a rigid body of the world that ended a substep
  /// not finite: "step 12: rigid body '#3': ..." (rigid_health.h)
  std::string message;
};

/// The solver's clock, health and every FEM body at a moment (FemSoftBodySolver::checkpoint).
struct FemCheckpoint {
  double time = 0;
  std::int64_t steps = 0;
  double last_dt = 0;
  FemSolverStatus status;
  std::vector<std::pair<const FemBody*, FemBodyCheckpoint>> bodies;
  /// Contact between FEM bodies: every pair's multipliers (empty while it is off).
  std::vector<FemPairCheckpoint> fem_pairs;
};

/// What to do when an FEM body touches a body it has no contact with (one of Bullet's soft bodies,
/// or another FEM body while contact between FEM bodies is off): they would pass through each
/// other.
enum class UnsupportedContact {
  kError,  ///< the solver fails (status().ok false) naming the pair: the default
  kWarn,   ///< a warning naming the pair, once per pair; the bodies pass through each other
};

class FemSoftBodySolver : public btSoftBodySolver {
 public:
  /// `settings`: the linear solver, tolerances and threads of every FEM body. Its time_step is
  /// not used here: Bullet's substep is the step (FemWorld uses it for its own stepSimulation).
  explicit FemSoftBodySolver(const SolverSettings& settings = {});
  ~FemSoftBodySolver() override;
  FemSoftBodySolver(const FemSoftBodySolver&) = delete;
  FemSoftBodySolver& operator=(const FemSoftBodySolver&) = delete;

  // ---- the world (torsion::attach calls these) ----
  /// Binds to the world that was constructed with this solver. Errors: the world steps its soft
  /// bodies with another solver; this solver is already bound to another world.
  Status bind(btSoftRigidDynamicsWorld& world);
  Status bind(btSoftMultiBodyDynamicsWorld& world);
  bool bound() const { return world_ != nullptr; }
  btDiscreteDynamicsWorld* world() const { return world_; }

  // ---- FEM bodies ----
  /// Adds an FEM body whose rest shape is `mesh` (linear tets) placed at `pose`, discretised with
  /// `element`, to the bound world. Errors: not bound, an empty mesh (no tets), a pose not finite
  /// or whose quaternion is off unit length by more than 1e-6 (closer, it is normalised), bad
  /// material, a duplicate name.
  ///
  /// `numbering` kCacheFriendly renumbers the mesh when that pays (mesh/input_numbering.h): the
  /// body's node and tet numbers then differ from the mesh's, and FemBody::inputNumbering()
  /// maps them (scene files and Python do so by default, and translate what they show).
  Result<FemBody*> addBody(const std::string& name, const TetMesh& mesh, const Material& material,
                           const Frame& pose = {}, ElementKind element = ElementKind::kTet4,
                           NodeNumbering numbering = NodeNumbering::kAsGiven);
  /// Removes the body from the world and destroys it (pointers to it and its hands are stale).
  void removeBody(FemBody* body);
  FemBody* body(const std::string& name) const;
  const std::vector<std::unique_ptr<FemBody>>& bodies() const { return bodies_; }

  // ---- the clock ----
  /// s, FEM time: the sum of the substeps taken since bind().
  double time() const { return time_; }
  /// FEM steps taken since bind().
  std::int64_t stepCount() const { return steps_; }
  /// s, length of the last FEM step (0 before the first).
  double lastTimeStep() const { return last_dt_; }

  // ---- checkpoints ----
  /// Clock, health and every FEM body's state and warm starts now (hands: Hand::checkpoint;
  /// Bullet's rigid bodies are the world's: FemWorld::checkpoint saves its own).
  FemCheckpoint checkpoint();
  /// Back to `checkpoint`: the FEM steps that follow are bit for bit the ones that followed it,
  /// given the same world around the bodies. Bodies added since are left as they are. Errors,
  /// changing nothing: a body of the checkpoint is not here (removed, or another world's).
  Status restore(const FemCheckpoint& checkpoint);

  // ---- health, warnings, settings ----
  const FemSolverStatus& status() const { return status_; }
  /// Things the user should know that did not stop the run (pairs that pass through each other
  /// under UnsupportedContact::kWarn), each said once.
  const std::vector<std::string>& warnings() const { return warnings_; }
  void setUnsupportedContact(UnsupportedContact policy) { unsupported_contact_ = policy; }
  /// Contact between FEM bodies (docs/contact.md, "Contact between FEM bodies"): on with default
  /// settings from construction; std::nullopt turns it off (touching FEM bodies are then
  /// UnsupportedContact). Errors, changing nothing: invalid settings.
  Status setFemContact(const std::optional<BodyContactSettings>& settings);
  /// Its islands and last substep's statistics, or nullptr when off.
  const FemContactIslands* femContact() const { return fem_contact_.get(); }

  const SolverSettings& solverSettings() const { return settings_; }
  /// Live edit between steps: linear solver, tolerance, caps (time_step is Bullet's). Errors,
  /// leaving the settings as they were: invalid settings, a different thread count.
  Status setSolverSettings(const SolverSettings& settings);
  const Parallel& parallel() const { return parallel_; }

  void addStepListener(StepListener* listener);
  void removeStepListener(StepListener* listener);

  // ---- btSoftBodySolver ----
  SolverTypes getSolverType() const override { return CPU_SOLVER; }
  bool checkInitialized() override { return true; }
  void optimize(btAlignedObjectArray<btSoftBody*>& soft_bodies, bool force_update = false) override;
  void copyBackToSoftBodies(bool /*move*/) override {}
  void predictMotion(btScalar solver_dt) override;
  void solveConstraints(btScalar solver_dt) override;
  void updateSoftBodies() override;
  void processCollision(btSoftBody* soft, const btCollisionObjectWrapper* other) override;
  void processCollision(btSoftBody* a, btSoftBody* b) override;

 private:
  FemBody* femBodyOf(const btSoftBody* soft) const;
  /// The coming substep's clock and gravity (no joints).
  StepContext substepContext(double dt) const;
  Status bindWorld(btDiscreteDynamicsWorld* world, btSoftBodyWorldInfo* info,
                   std::function<void(btSoftBody*)> add, std::function<void(btSoftBody*)> remove);
  void unsupportedPair(const btSoftBody* a, const btSoftBody* b);
  std::string describe(const btSoftBody* soft) const;
  void fail(std::string message);

  SolverSettings settings_;
  Parallel parallel_;
  btDefaultSoftBodySolver bullet_solver_;  // steps Bullet's own soft bodies
  btAlignedObjectArray<btSoftBody*> bullet_bodies_;

  btDiscreteDynamicsWorld* world_ = nullptr;
  btSoftBodyWorldInfo* world_info_ = nullptr;
  std::function<void(btSoftBody*)> add_to_world_, remove_from_world_;
  sap::JointLedger joint_ledger_;  // the world's joints, each substep (predictMotion on)

  std::vector<std::unique_ptr<FemBody>> bodies_;
  std::unique_ptr<FemContactIslands> fem_contact_;  // nullptr: FEM-FEM contact off
  IslandWorkspace island_workspace_;                // the island steps' storage
  std::unique_ptr<SoftBodyTouch> soft_touch_;       // whether Bullet's soft bodies touch ours
  std::vector<StepListener*> listeners_;
  bool rigid_step_announced_ = false;  // beforeRigidStep went out this substep

  double time_ = 0;
  double last_dt_ = 0;
  std::int64_t steps_ = 0;
  FemSolverStatus status_;
  std::vector<std::string> warnings_;
  UnsupportedContact unsupported_contact_ = UnsupportedContact::kError;
  std::set<std::pair<const btSoftBody*, const btSoftBody*>> reported_pairs_;
};

/// Binds the world's FemSoftBodySolver to it and returns it. Errors, with what to do: the world
/// was constructed without a FemSoftBodySolver (Bullet takes its soft-body solver only at
/// construction), or its solver is bound to another world.
Result<FemSoftBodySolver*> attach(btSoftRigidDynamicsWorld& world);
Result<FemSoftBodySolver*> attach(btSoftMultiBodyDynamicsWorld& world);

}  // namespace torsion
