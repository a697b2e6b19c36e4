#pragma once
// SceneSpec -> a live FemWorld: meshes loaded, bodies placed, node sets selected and attached,
// rigid bodies added. Errors name the scene file and the entry.

#include <memory>
#include <string>
#include <vector>

#include "scene_spec.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/result.h"

namespace torsion::scene {

struct NodeSetHandle {
  std::string name;
  FemBody* body = nullptr;
  int group = -1;
  Eigen::Vector3d wrench_about = Eigen::Vector3d::Zero();
  int node_count = 0;
};

struct BuiltScene {
  SceneSpec spec;
  std::unique_ptr<FemWorld> world;
  std::vector<NodeSetHandle> node_sets;
  std::vector<std::string> warnings;  ///< from mesh loading
};

/// Nodes of `mesh` whose rest positions fall in `selection`.
std::vector<int> selectNodes(const TetMesh& mesh, const NodeSelection& selection);

/// threads >= 0 overrides the scene's solver.threads.
Result<std::unique_ptr<BuiltScene>> buildScene(SceneSpec spec, int threads_override = -1);

}  // namespace torsion::scene
