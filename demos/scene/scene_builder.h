#pragma once
// SceneSpec -> a live FemWorld: meshes loaded, bodies placed, node sets selected and attached,
// rigid bodies added. Errors name the scene file and the entry.

#include <memory>
#include <string>
#include <vector>

#include "rigid_body_builder.h"
#include "scene_spec.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/result.h"

namespace torsion::scene {

struct NodeSetHandle {
  std::string name;
  FemBody* body = nullptr;
  int group = -1;
  Eigen::Vector3d wrench_about = Eigen::Vector3d::Zero();
  int node_count = 0;
};

/// A scene hand: its script (spec) and the live Hand. Hands whose grab_at is 0 have already
/// grabbed when buildScene returns, so a plane that misses is an error before any step.
struct SceneHand {
  HandSpec spec;
  std::unique_ptr<Hand> hand;
  bool released = false;
  /// false: its script neither grabs, moves nor releases it any more (the viewer took it): it
  /// stays where its last mover left it.
  bool scripted = true;
};

class SceneHaptics;  // scene_haptics.h

struct BuiltScene {
  SceneSpec spec;
  /// rigid_bodies[] in file order (not the ground). Declared before `world`, so the kinematic
  /// bodies' motion states outlive the world that points to them.
  std::vector<SceneRigidBody> rigid_bodies;
  std::unique_ptr<FemWorld> world;
  std::vector<NodeSetHandle> node_sets;
  std::vector<SceneHand> hands;
  std::vector<std::string> warnings;  ///< from mesh loading
  /// Devices, haptic loops and couplings of the device hands (null when none); last, so it is
  /// destroyed first: it holds the hands and the world by reference.
  std::shared_ptr<SceneHaptics> haptics;
};

/// Nodes of `mesh` whose rest positions fall in `selection`.
std::vector<int> selectNodes(const TetMesh& mesh, const NodeSelection& selection);

/// Grabs, releases and moves every scripted scene hand (device hands are the haptics' job) for the
/// step from world time t to t + dt: call before each FemWorld::step(). Errors: a scripted grab
/// whose plane misses the body.
Status driveHands(BuiltScene& scene);

/// How buildScene builds for its caller.
struct BuildOptions {
  int threads = -1;  ///< >= 0: overrides the scene's solver.threads
  /// Tools may have `manual` devices: only `torsion view` has the mouse and keys that move them
  /// (it finds them with SceneHaptics::manualTool). Off, such a scene is an error naming the
  /// tool, before anything is loaded.
  bool manual_devices = false;
};

Result<std::unique_ptr<BuiltScene>> buildScene(SceneSpec spec, const BuildOptions& options = {});

}  // namespace torsion::scene
