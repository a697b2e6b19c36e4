#pragma once
// What one picture shows, as plain data taken from a live scene: the surfaces of the FEM bodies
// (positions, outward per-vertex normals, von Mises stress per vertex, grabbed nodes), the rigid
// bodies, the hands (frame and plane), the wrenches and the HUD text. No GL here: the renderer
// draws a FrameData, the tests perturb one (drop a body, flip normals) to prove the picture
// comparison notices.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rigid_geometry.h"
#include "scene_builder.h"
#include "torsion/constraints/frame.h"

namespace torsion::render {

struct BodyDrawData {
  std::string name;
  std::vector<Eigen::Vector3f> positions;     ///< per node, m
  std::vector<Eigen::Vector3f> normals;       ///< per node: area-weighted outward surface normal
  std::vector<float> stress;                  ///< per node: von Mises stress, Pa (mean of its tets)
  std::vector<int> grabbed_nodes;             ///< nodes held by a hand, drawn orange
  std::vector<std::array<int, 3>> triangles;  ///< surface, counter-clockwise from outside
  /// Surface nodes that lie on straight lines along an elongated body's rest shape (four, a
  /// quarter turn apart), each in order: drawn as lines, they wind into helices when the body
  /// twists and curve when it bends. Empty for a body that is not at least twice as long as wide.
  std::vector<std::vector<int>> stripes;
};

/// The stripes of BodyDrawData for `mesh` (from its rest positions).
std::vector<std::vector<int>> restStripes(const TetMesh& mesh);

struct HandDrawData {
  std::string name;
  Frame frame;  ///< O and R = [i j k]
  bool holding = false;
  double plane_half_size = 1;  ///< m, half the side of the drawn square of the plane
};

struct WrenchReadout {
  std::string name;                                  ///< hand or node set
  Eigen::Vector3d force = Eigen::Vector3d::Zero();   ///< N, what the body exerts on it
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  ///< N m
};

/// The recent history of one wrench, oldest first, for the viewer's scrolling plot.
struct WrenchHistory {
  std::string name;
  std::vector<double> times;             ///< s
  std::vector<Eigen::Vector3d> forces;   ///< N
  std::vector<Eigen::Vector3d> torques;  ///< N m
};

struct FrameData {
  std::string title;
  double time = 0;  ///< s
  int step = 0;
  double steps_per_second = 0;  ///< <= 0: not shown
  Eigen::Vector3d gravity = Eigen::Vector3d::Zero();
  std::vector<BodyDrawData> bodies;
  std::vector<RigidDrawData> rigids;
  std::vector<HandDrawData> hands;
  std::vector<WrenchReadout> wrenches;
  double stress_max = 1;             ///< Pa, top of the colour map (bottom is 0)
  Eigen::AlignedBox3d bounds;        ///< FEM bodies, finite rigid bodies and hand origins
  std::vector<std::string> notes;    ///< extra HUD lines (the viewer's settings and keys)
  std::vector<WrenchHistory> plots;  ///< scrolling force and torque plots (the viewer's hand)
  scene::CameraSpec camera;          ///< the scene's camera wishes (frameCamera)
};

/// Von Mises stress per tet, Pa: of the corotated linear material, sigma = 2 mu eps +
/// lambda tr(eps) I with eps = sym(R^T F) - I, R the tet's rotation of the last step; of a
/// hyperelastic law (Material::law), its Cauchy stress P F^T / J.
std::vector<double> tetVonMises(const FemBody& body);

/// The smallest of 1, 2, 2.5, 5 times a power of ten that is >= value (> 0): a legend's top.
double niceCeiling(double value);

/// Takes a picture's worth of data from the scene as it is now. Wrenches are those of the last
/// step (zero before the first). stress_max is niceCeiling of the largest surface value, and at
/// least the stress of a 1e-6 strain (so a body at rest shows uniform blue, not round-off).
FrameData captureFrame(scene::BuiltScene& scene, double steps_per_second = 0);

/// Adds a hand the scene does not list (one a program added to the world): drawn at its patch
/// while it holds, else at `free_frame`, its wrench listed after those already in `frame`.
/// captureFrame adds the scene's hands this way; call before the bounds are used (frameCamera).
void addHand(FrameData& frame, const Hand& hand, const std::string& name, const Frame& free_frame);

/// The colour map of the stress: a dark-blue, teal, green, yellow ramp of increasing lightness
/// (no orange, which marks grabbed nodes). s in [0, 1], clamped.
Eigen::Vector3d stressColour(double s);

}  // namespace torsion::render
