#pragma once
// Bullet's own deformable world (btDeformableMultiBodyDynamicsWorld) on a scene file: the same
// meshes, node sets, rigid bodies, gravity and dt as Torsion's run (bench_rigid_mix.cpp).

#include <string>
#include <vector>

#include "scene_spec.h"

namespace torsion::bench {

struct MixRun {
  bool ok = true;
  std::string message;  ///< why not ok
  int steps = 0;
  std::vector<double> step_ms;
  double max_node_speed = 0;          ///< m/s over the run
  std::vector<double> rigid_final_z;  ///< per rigid body, centre height at the end
  std::string detail;                 ///< solver settings
};

MixRun runBulletMix(const scene::SceneSpec& spec, int steps);

}  // namespace torsion::bench
