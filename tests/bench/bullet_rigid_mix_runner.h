#pragma once
// Bullet's own deformable world (btDeformableMultiBodyDynamicsWorld) on a scene file: the same
// meshes, node sets, rigid bodies (static, dynamic and kinematic on their scripts), gravity and dt
// as Torsion's run (bench_rigid_mix.cpp, bench_bullet_demos.cpp). Hands are not mapped.

#include <Eigen/Core>
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
  /// The end state for the outcome checks (bench_demo_checks.h): per FEM body (scene order) its
  /// node positions, per rigid body (scene order, not the ground) its pose.
  std::vector<std::vector<Eigen::Vector3d>> final_nodes;
  std::vector<Frame> rigid_final_pose;
  std::string detail;  ///< solver settings
};

MixRun runBulletMix(const scene::SceneSpec& spec, int steps);

}  // namespace torsion::bench
