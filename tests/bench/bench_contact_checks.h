#pragma once
// Checks of contact between FEM bodies for the side-by-side contact benchmark
// (bench_fem_contact.cpp), asked the same way of Torsion's and Bullet's states, from node
// positions and velocities alone:
//   interpenetration  nodes of one body inside another body's deformed tet mesh, and how deep
//                     (distance to that body's deformed surface): at the end and over every step
//   momentum          sum of m v (lumped masses rho V / 4 on the rest mesh, what both engines
//                     use) against the start's, for scenes without gravity, ground or rigid bodies
//   kinetic energy    against the start's: a collision may not add energy
//   outcome           the scene's defining result (soft_stack: the stack still stands in order
//                     with the ball on top, ...); "n/a" for a scene without a rule here

#include <Eigen/Core>
#include <string>
#include <vector>

#include "scene_spec.h"
#include "torsion/mesh/tet_mesh.h"

namespace torsion::bench {

using NodeField = std::vector<std::vector<Eigen::Vector3d>>;  ///< per FEM body, per node

/// The deepest node of any body inside any other body (m, 0 when none is inside) and how many
/// nodes lie deeper than `tolerance`.
struct Penetration {
  double deepest = 0;
  int nodes_beyond = 0;
};
Penetration interpenetration(const std::vector<TetMesh>& rest, const NodeField& x,
                             double tolerance);

/// Per FEM body, its nodes' lumped masses rho V / 4 (kg).
std::vector<std::vector<double>> lumpedMasses(const scene::SceneSpec& spec,
                                              const std::vector<TetMesh>& rest);

struct Motion {
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();  ///< N s
  double kinetic_energy = 0;                           ///< J
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();    ///< m, centre of mass
};
Motion motionOf(const std::vector<std::vector<double>>& masses, const NodeField& x,
                const NodeField& v);

/// What one engine's run left, for judgeContact.
struct ContactEnd {
  bool finite = true;
  NodeField nodes, velocities;
  Penetration at_end;
  Penetration worst;    ///< over every step
  int worst_step = -1;  ///< the step (0-based) of `worst`
};

struct ContactVerdict {
  bool passed_through = false;  ///< a node deeper than the tolerance, at the end or on any step
  /// "kept", "lost" (|change| > 5 % of sum m |v0|) or "n/a" (gravity, ground or rigid bodies).
  std::string momentum = "n/a";
  bool energy_gained = false;   ///< kinetic energy at the end above 1.05 times the start's
  std::string outcome = "n/a";  ///< "ok", "failed" or "n/a"
  std::string detail;
};

/// `start`: the scene's initial motion (motionOf on the rest positions and initial velocities).
ContactVerdict judgeContact(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest,
                            const std::vector<std::vector<double>>& masses, const Motion& start,
                            const ContactEnd& end, double tolerance);

/// The initial node velocities the scene gives (linear + angular x (x - c), c the body's centre
/// of mass), with the rest positions placed as the scene places them.
NodeField initialVelocities(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest,
                            const std::vector<std::vector<double>>& masses);

}  // namespace torsion::bench
