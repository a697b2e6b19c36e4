#pragma once
// Outcome checks of the side-by-side demo benchmark (bench_bullet_demos.cpp): the same questions
// asked of Torsion's end state and of Bullet's, from node positions and rigid poses alone.
//   exploded        a non-finite node, or a node faster than the scene's solver max_speed (1000
//                   m/s by default: Torsion's own blow-up criterion) during the run
//   sank            an FEM node or a dynamic box below the ground by more than the tolerance
//   passed_through  an FEM node inside a box rigid body by more than the tolerance at the end
//   outcome         the scene's defining result (bullet_pinch: the cube lifted and held, ...);
//                   "n/a" for a scene without a rule here

#include <Eigen/Core>
#include <string>
#include <vector>

#include "scene_spec.h"

namespace torsion::bench {

struct EndState {
  bool finite = true;
  double max_node_speed = 0;                        ///< m/s over the run
  std::vector<std::vector<Eigen::Vector3d>> nodes;  ///< per FEM body, scene order
  std::vector<Frame> rigid;                         ///< per rigid body, scene order
};

struct Verdict {
  bool exploded = false;
  bool sank = false;
  bool passed_through = false;
  std::string outcome = "n/a";  ///< "ok", "failed" or "n/a"
  std::string detail;           ///< numbers behind the verdicts
};

/// steps: how many the end state is after; tolerance in m (both engines keep nodes a margin off
/// surfaces; Bullet's is 0.01 m here).
Verdict judge(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest, const EndState& end,
              int steps, double tolerance);

}  // namespace torsion::bench
