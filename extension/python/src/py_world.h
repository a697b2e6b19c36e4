#pragma once
// The C++ side of torsion.World: a built scene (demos/scene, the loader `torsion run` uses) plus
// what Python adds in code (hands it drives itself), stepped and checkpointed as one. Python-free
// on purpose: the bindings (bind_*.cpp) translate its errors into exceptions and its storage into
// numpy arrays.

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "device_parser.h"
#include "scene_builder.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/constraints/carried_nodes.h"
#include "torsion/result.h"
#include "vtk_series.h"

namespace torsion::python {

/// Why a call failed, so the bindings raise the matching exception.
/// kOutput: a file that could not be written (OSError).
enum class FailureKind { kScene, kMesh, kUnstable, kValue, kOutput };

struct Failure {
  FailureKind kind = FailureKind::kValue;
  std::string message;  ///< the CLI's message, word for word
};

/// Everything the next steps of a PyWorld read. In memory (`world`, `hands`, ...: the solver's warm
/// starts and shared motion state by pointer) and, for states Python holds, also as `bytes`
/// (bullet/checkpoint_io.h), which is all an unpickled state has.
struct PyWorldState {
  bool in_memory = true;  ///< false: only `bytes` (and `time`) hold it
  double time = 0;        ///< s
  std::string bytes;      ///< the serialised form (PyWorld::serialize), or empty
  WorldCheckpoint world;
  std::vector<HandCheckpoint> hands;  ///< scene hands, then hands added in code
  std::vector<bool> released;         ///< per scene hand: let go for good (driveHands)
  size_t node_set_count = 0;
  std::string failure;
  /// PyWorld::removeRigidBody calls before it was saved: the in-memory part points to the rigid
  /// bodies there were then.
  std::uint64_t rigid_removals = 0;
  /// The world that saved it (PyWorld::id()); the in-memory part refers to that world's parts, so
  /// another world reads `bytes` instead.
  std::uint64_t source = 0;
};

class PyWorld {
 public:
  /// A scene file, or a demo scene's name resolved like `torsion run NAME`. threads < 0: the
  /// scene's own solver.threads.
  /// `devices` are `torsion run`'s --device / --haptics / --allow-remote-device choices.
  static Result<std::unique_ptr<PyWorld>> fromScene(const std::string& name_or_path, int threads,
                                                    const scene::DeviceOverrides& devices,
                                                    FailureKind* kind);
  /// An empty world (bodies, node sets, hands and rigid bodies added in code).
  explicit PyWorld(const WorldSettings& settings);

  scene::BuiltScene& scene() { return *scene_; }
  /// Unique among the worlds of this process (never reused), for PyWorldState::source.
  std::uint64_t id() const { return id_; }
  /// What from_scene was given (a scene's name or path), or empty for a world built in code.
  const std::string& sceneSource() const { return scene_source_; }
  /// from_scene's threads argument.
  int sceneThreads() const { return scene_threads_; }
  /// Whether Python added bodies, node sets, hands or rigid bodies (then the scene alone does not
  /// describe the world).
  bool partsAdded() const { return parts_added_; }
  /// Whether from_scene was given devices or a haptics mode.
  bool devicesOverridden() const { return devices_overridden_; }
  /// Whether Python set a rigid body's kinematic target (a checkpoint holds poses, not targets).
  bool hasKinematicTargets() const { return !targets_.empty(); }
  /// Whether Python removed a rigid body (removeRigidBody), drove a node set (moveNodeSet) or
  /// changed the contact between FEM bodies (setFemContact): what the scene does not describe.
  bool rigidRemoved() const { return rigid_removals_ > 0; }
  bool nodeSetsDriven() const { return !drives_.empty(); }
  bool femContactChanged() const { return fem_contact_changed_; }
  FemWorld& world() { return *scene_->world; }

  /// n steps (scripted hands driven, device hands through their haptics, as `torsion run`).
  /// Stops at the first failing step; the world is then back at the end of the last good step
  /// (bodies, hands, clock; not with device hands) and every later step fails with the same
  /// message until restoreState().
  /// `interrupted`, when given, is asked after every step; true stops the run there, at a step
  /// boundary (the world as after a shorter step(n)), and step returns Ok.
  /// While a series is recorded (recordSeries), each step due is written inside the loop; a
  /// file that cannot be written ends the series and step with kOutput (the world is as after
  /// the steps done).
  Result<Ok> step(int n, FailureKind* kind, const std::function<bool()>& interrupted = {});

  /// Starts the ParaView series of `torsion run --vtk-every` (demos/series/vtk_series.h) in
  /// `directory`: series/ emptied of .vtu files, the state now written as its first entry, and
  /// then every `every`-th step after it. Errors, changing nothing, with kValue: every < 1, a
  /// series already recorded, a directory that cannot be created; with kOutput: a file that
  /// cannot be written (the series is not started).
  Status recordSeries(const std::string& directory, int every, FailureKind* kind);
  /// Writes the state now unless it was the last written and ends the series (nothing without
  /// one). An error (kOutput) names the file; the series ends all the same.
  Status stopSeries();
  bool recordingSeries() const { return series_ != nullptr; }
  /// Steps written by the series recorded now, else by the last one (0 without any).
  int seriesStepsWritten() const {
    return series_ ? series_->stepsWritten() : series_steps_written_;
  }

  /// Adds a body from a mesh file (MeshError on a bad file) or from a built mesh. Names of
  /// bodies, node sets, hands and rigid bodies follow the scene file's rule (scene::nameFault)
  /// and are unique among their kind.
  Result<FemBody*> addBody(const std::string& name, const TetMesh& mesh, const Material& material,
                           const Frame& pose, ElementKind element, NodeNumbering numbering);
  /// A node set (a fixed or carried group) over `nodes` of `body`; returns its index.
  Result<int> addNodeSet(const std::string& name, FemBody& body, std::vector<int> nodes,
                         const Eigen::Vector3d& wrench_about);
  Result<Hand*> addHand(FemBody& body, const std::string& name, const HandSettings& settings);
  /// All hands: the scene's (in file order), then those added in code.
  std::vector<Hand*> hands();
  /// The scene's spec of hand h, or null for a hand added in code.
  const scene::HandSpec* handSpec(const Hand& hand) const;
  /// A rigid body (or, `ground`, the ground plane) after the scene parser's checks of its values:
  /// lengths in (0, 1e6] m, mass 0 (static) or in [1e-9, 1e12] kg, all finite (errors name the
  /// add_rigid_body / add_ground argument and its value).
  Result<btRigidBody*> addRigidBody(const scene::RigidBodySpec& spec, bool ground);
  /// Takes a rigid body (the scene's or one added in code, not the ground) out of the world for
  /// good (FemWorld::removeRigidBody), with what Python queued for it (loads, kinematic target).
  /// contacts() is empty until the next step, and states saved before no longer restore. Errors,
  /// changing nothing, starting "remove_rigid_body 'name': ": an FEM body anchors nodes to it.
  Status removeRigidBody(btRigidBody& body);
  /// Nonzero while `body` is one of the world's rigid bodies: a number never given to another
  /// body of this world (a removed body's address may come back as a new body's, its serial not).
  std::uint64_t rigidSerial(const btRigidBody* body) const;

  /// Node set `index` (scene().node_sets) driven like a mocap body: its frame reaches `pose` at
  /// the end of the next step and stays there until the next call. The set's frame starts at its
  /// wrench_about point with the world's axes; its nodes are carried rigidly with it. Errors,
  /// changing nothing, starting "move_to: node set 'name': ": a released set, a set its scene file
  /// moves, a position beyond scene::kMaxPlacement.
  Status moveNodeSet(size_t index, const Frame& pose);
  /// Where node set `index`'s frame is at the end of the next step (held: where it started).
  Frame nodeSetFrame(size_t index);
  /// Whether node set `index` follows a motion of its scene file.
  bool nodeSetScripted(size_t index) const;

  /// Contact between FEM bodies from the next step on (FemSoftBodySolver::setFemContact):
  /// `settings`, or off (nullopt). Off, FEM bodies that touch pass through each other, or with
  /// `refuse_touching` fail the step as a scene's "enabled": false does. Errors, changing
  /// nothing: invalid settings.
  Status setFemContact(const std::optional<BodyContactSettings>& settings, bool refuse_touching);

  /// Gravity for the next steps, m/s^2 (FEM and dynamic rigid bodies): finite, magnitude at most
  /// a scene file's bound (scene::checkGravity). Errors change nothing.
  Status setGravity(const Eigen::Vector3d& gravity);
  /// dt for the next steps, s, within SolverSettings' bounds; the clock goes on from where it is.
  /// Errors, changing nothing: out of bounds; a world whose scene runs device hands (their
  /// haptic loops keep the dt they started with).
  Status setTimeStep(double dt);

  Result<PyWorldState> saveState();
  /// Back to `state`; a state of bytes alone is read for this world first (errors: corrupted
  /// bytes, or a world other than the one saved).
  Status restoreState(const PyWorldState& state);
  /// The bytes of a state saved from this world (saveState), pickled as torsion.State.
  std::string serialize(const PyWorldState& state);

  /// Python changed the world between steps (forces, hand goals, grabs, materials, parts): a
  /// failing step can no longer be rewound by replaying from before that change.
  void touched() { anchor_.reset(); }

  /// Serialises the calls that change the world against a step running without the GIL.
  std::mutex& busy() { return busy_; }

  /// Whether the solvers' contact lists describe the world as it is: a step was taken since it
  /// was built or last restored (py_contacts.h).
  bool stepped() const { return stepped_; }

  /// The scene's record of one of this world's rigid bodies, or null (the ground).
  const scene::SceneRigidBody* sceneRigidBody(const btRigidBody& body) const;

  /// Python's inputs to rigid bodies (py_rigid.h), handed to Bullet before each step: a load
  /// (force N, torque N m about the centre of mass) for the next step only, added to what is
  /// already queued; and a kinematic target, kept until the next one.
  void queueLoad(btRigidBody& body, const Wrench& load);
  /// What is queued for `body`'s next step (zero when nothing is).
  Wrench queuedLoad(const btRigidBody& body) const;
  void setKinematicTarget(btRigidBody& body, const btTransform& target);
  /// The pose Python set as `body`'s kinematic target, or null.
  const btTransform* kinematicTarget(const btRigidBody& body) const;

 private:
  struct RigidLoad {
    btRigidBody* body = nullptr;
    Wrench load;
  };
  struct KinematicTarget {
    btRigidBody* body = nullptr;
    btTransform target;
  };
  PyWorld();
  /// Before a step: every kinematic target to its body's motion state (where Bullet reads it),
  /// and `loads` to Bullet's force accumulators (which it clears after the step).
  void applyRigidInputs(const std::vector<RigidLoad>& loads);
  /// Every body's material as built (set_material changes the live one), by body name: a state
  /// restores into a world whose bodies were built as the saved world's were.
  void recordBuiltMaterials();
  void registerRigid(const btRigidBody* body) { rigid_serials_[body] = next_rigid_serial_++; }
  /// The driven node sets' groups to their drives (a restored group has the motion it was saved
  /// with: the drive is the world's, as a kinematic target is).
  void installDrives();
  std::unique_ptr<scene::BuiltScene> scene_;
  std::uint64_t id_ = 0;
  std::string scene_source_;
  int scene_threads_ = -1;
  bool parts_added_ = false;
  bool devices_overridden_ = false;
  std::map<std::string, Material> built_materials_;
  std::vector<std::unique_ptr<Hand>> own_hands_;
  std::string failure_;  // set by the first failed step; the world does not go on after it
  static constexpr int kAnchorEvery = 64;  // steps between rewind checkpoints (step())
  std::optional<PyWorldState> anchor_;     // where a failed step rewinds to and replays from
  int anchor_step_ = 0;                    // world().stepCount() at anchor_
  std::vector<RigidLoad> loads_;           // queued for the next step
  std::vector<RigidLoad> anchor_loads_;    // those the step from anchor_ took: replayed with it
  std::vector<KinematicTarget> targets_;   // set from Python, handed to Bullet before each step
  bool stepped_ = false;                   // stepped(): reset by restoreState
  std::map<const btRigidBody*, std::uint64_t> rigid_serials_;  // rigidSerial()
  std::uint64_t next_rigid_serial_ = 1;
  std::uint64_t rigid_removals_ = 0;
  // A driven node set's goal (its frame, as move_to gave it) and the displacement that carries
  // its nodes there (x = R x0 + O from where they were when the set was made), which the motion
  // of its group reads.
  struct NodeSetDrive {
    Frame goal;
    Frame displacement;
  };
  std::map<size_t, std::shared_ptr<NodeSetDrive>> drives_;  // by node set index
  bool fem_contact_changed_ = false;
  std::unique_ptr<series::VtkSeries> series_;  // recordSeries() until stopSeries()
  int series_steps_written_ = 0;               // by the last series ended
  /// Ends the series after a write error: "record_series: <message>".
  Error endSeriesWith(const std::string& message);
  std::mutex busy_;
};

}  // namespace torsion::python
