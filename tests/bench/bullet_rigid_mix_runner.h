#pragma once
// Bullet's own deformable world (btDeformableMultiBodyDynamicsWorld) on a scene file: the same
// meshes, node sets, rigid bodies (static, dynamic and kinematic on their scripts), gravity and dt
// as Torsion's run (bench_rigid_mix.cpp, bench_bullet_demos.cpp). Hands are not mapped.

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "scene_spec.h"

namespace torsion::bench {

/// Node positions per FEM body (scene order), after a step.
using NodeFrames = std::vector<std::vector<Eigen::Vector3d>>;

struct MixOptions {
  double margin = 0.01;  ///< m, every soft body's collision margin
  /// Bullet steps of dt / substeps per scene step (Bullet's contact demos take 4 of 1/240 s).
  int substeps = 1;
  /// The scene's ground (a plane facing +z) as a 100 x 100 x 10 m box with its top at the ground,
  /// as Bullet's own demos set up their ground.
  bool ground_as_box = false;
  /// Called after each step with its index (0-based) and the nodes, outside the timed region.
  std::function<void(int, const NodeFrames&)> after_step;
};

struct MixRun {
  bool ok = true;
  std::string message;  ///< why not ok
  int steps = 0;
  std::vector<double> step_ms;      ///< wall time of each stepSimulation
  std::vector<double> step_cpu_ms;  ///< process CPU time of each stepSimulation
  /// Process CPU time per step inside Bullet's collision detection (its profile zones
  /// performDiscreteCollisionDetection, "Deformable Collision" and performGeometricCollisions, not
  /// counted twice when nested) and inside its solve (solveConstraints).
  std::vector<double> detect_cpu_ms, solve_cpu_ms;
  double max_node_speed = 0;          ///< m/s over the run
  std::vector<double> rigid_final_z;  ///< per rigid body, centre height at the end
  /// The end state for the outcome checks (bench_demo_checks.h): per FEM body (scene order) its
  /// node positions, per rigid body (scene order, not the ground) its pose.
  NodeFrames final_nodes;
  NodeFrames final_velocities;  ///< m/s, per FEM body and node
  std::vector<Frame> rigid_final_pose;
  std::string detail;  ///< solver settings
};

/// FEM bodies start with the scene's linear and angular velocity (about their centre of mass). With
/// two or more FEM bodies and the scene's fem_contact on, they collide with each other as in
/// Bullet's DeformableContact and PinchFriction demos: VF_DD (nodes against the other body's
/// faces within the two margins) plus the world's continuous node-face test between soft bodies.
/// Friction: the scene's FEM pair coefficient mu is Bullet's kDF * kDF, so kDF = sqrt(mu), and
/// rigid bodies' friction is divided by kDF so that node-rigid pairs keep the scene's value.
MixRun runBulletMix(const scene::SceneSpec& spec, int steps, const MixOptions& options = {});

}  // namespace torsion::bench
