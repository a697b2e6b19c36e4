#include "frame_data.h"

#include <algorithm>
#include <cmath>

#include "scene_haptics.h"
#include "torsion/fem/corotated_element.h"
#include "torsion/fem/hyperelastic.h"

namespace torsion::render {

namespace {

double vonMises(const Eigen::Matrix3d& s) {
  const double vm2 =
      0.5 * ((s(0, 0) - s(1, 1)) * (s(0, 0) - s(1, 1)) + (s(1, 1) - s(2, 2)) * (s(1, 1) - s(2, 2)) +
             (s(2, 2) - s(0, 0)) * (s(2, 2) - s(0, 0))) +
      3 * (s(0, 1) * s(0, 1) + s(1, 2) * s(1, 2) + s(0, 2) * s(0, 2));
  return std::sqrt(std::max(0.0, vm2));
}

// The Cauchy stress of a hyperelastic law, sigma = P F^T / J (P F^T at J <= 0: an inverted tet
// has no Cauchy stress, its Kirchhoff stress still shows the load).
template <class Law>
Eigen::Matrix3d cauchyStress(const Law& law, const Eigen::Matrix3d& F) {
  const double J = F.determinant();
  const Eigen::Matrix3d tau = firstPiola(law, F) * F.transpose();
  return J > 0 ? Eigen::Matrix3d(tau / J) : tau;
}

}  // namespace

std::vector<double> tetVonMises(const FemBody& body) {
  const FemModel& model = body.model();
  const TetMesh& mesh = model.mesh();
  const FemState& state = body.state();
  const Material& material = model.material();
  const double mu = material.mu(), lambda = material.lambda();
  const StableNeoHookean neo_hookean =
      StableNeoHookean::fromYoungPoisson(material.youngs_modulus, material.poisson_ratio);
  const MooneyRivlin mooney_rivlin = MooneyRivlin::fromYoungPoisson(
      material.youngs_modulus, material.poisson_ratio, material.mooney_rivlin_c2_fraction);
  std::vector<double> result(static_cast<size_t>(mesh.tetCount()));
  for (int t = 0; t < mesh.tetCount(); ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    std::array<Eigen::Vector3d, 4> x;
    for (int a = 0; a < 4; ++a)
      x[static_cast<size_t>(a)] = state.position(tet[static_cast<size_t>(a)]);
    const Eigen::Matrix3d F =
        deformationGradient(x, model.tetRestData()[static_cast<size_t>(t)].rest_shape_inverse);
    if (material.law == MaterialLaw::kStableNeoHookean) {
      result[static_cast<size_t>(t)] = vonMises(cauchyStress(neo_hookean, F));
      continue;
    }
    if (material.law == MaterialLaw::kMooneyRivlin) {
      result[static_cast<size_t>(t)] = vonMises(cauchyStress(mooney_rivlin, F));
      continue;
    }
    // The rotation of the element the tet belongs to (tet10: the sub-tet's element).
    const size_t element = static_cast<size_t>(model.elementOfTet(t));
    const Eigen::Matrix3d R = element < state.element_rotations.size()
                                  ? state.element_rotations[element].toRotationMatrix()
                                  : Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d RtF = R.transpose() * F;
    const Eigen::Matrix3d eps = 0.5 * (RtF + RtF.transpose()) - Eigen::Matrix3d::Identity();
    result[static_cast<size_t>(t)] =
        vonMises(2 * mu * eps + lambda * eps.trace() * Eigen::Matrix3d::Identity());
  }
  return result;
}

double niceCeiling(double value) {
  if (!(value > 0) || !std::isfinite(value)) return 1;
  const double decade = std::pow(10.0, std::floor(std::log10(value)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * decade >= value * (1 - 1e-12)) return m * decade;
  }
  return 10 * decade;
}

Eigen::Vector3d stressColour(double s) {
  // Control points chosen for this project: lightness rises monotonically, so the map also
  // reads in grey.
  static const std::array<Eigen::Vector3d, 5> kStops = {
      Eigen::Vector3d(0.16, 0.11, 0.42), Eigen::Vector3d(0.13, 0.38, 0.62),
      Eigen::Vector3d(0.12, 0.62, 0.58), Eigen::Vector3d(0.50, 0.80, 0.32),
      Eigen::Vector3d(0.98, 0.93, 0.30)};
  s = std::clamp(std::isfinite(s) ? s : 0.0, 0.0, 1.0) * static_cast<double>(kStops.size() - 1);
  const size_t i = std::min(static_cast<size_t>(s), kStops.size() - 2);
  const double f = s - static_cast<double>(i);
  return (1 - f) * kStops[i] + f * kStops[i + 1];
}

std::vector<std::vector<int>> restStripes(const TetMesh& mesh) {
  const Eigen::Vector3d lo = mesh.boundsMin(), hi = mesh.boundsMax();
  const Eigen::Vector3d extent = hi - lo, centre = 0.5 * (lo + hi);
  int a = 0;
  extent.maxCoeff(&a);
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  if (extent[a] < 2 * std::max(extent[b], extent[c]) || extent[b] <= 0 || extent[c] <= 0) return {};
  // Nodes on the outline of the cross-section within +-0.15 rad of each quarter direction; of
  // those, one per slice of the length (the closest in angle), so a fine mesh gives a straight
  // line, not a zigzag between neighbours side by side.
  constexpr int kSlices = 48;
  struct Pick {
    double off = 1e9;
    int node = -1;
  };
  std::vector<std::array<Pick, kSlices>> lines(4);
  for (int i : mesh.surfaceNodes()) {
    const Eigen::Vector3d& p = mesh.restPositions()[static_cast<size_t>(i)];
    const double u = 2 * (p[b] - centre[b]) / extent[b], v = 2 * (p[c] - centre[c]) / extent[c];
    if (std::hypot(u, v) < 0.8) continue;  // an end face, inside the outline
    const double angle = std::atan2(v, u);
    const int slice =
        std::clamp(static_cast<int>((p[a] - lo[a]) / extent[a] * kSlices), 0, kSlices - 1);
    for (size_t k = 0; k < 4; ++k) {
      const double off =
          std::abs(std::remainder(angle - static_cast<double>(k) * M_PI / 2, 2 * M_PI));
      Pick& pick = lines[k][static_cast<size_t>(slice)];
      if (off < 0.15 && off < pick.off) pick = {off, i};
    }
  }
  std::vector<std::vector<int>> stripes;
  for (const auto& line : lines) {
    std::vector<int> nodes;
    for (const Pick& pick : line) {
      if (pick.node >= 0) nodes.push_back(pick.node);
    }
    if (nodes.size() >= 3) stripes.push_back(std::move(nodes));
  }
  return stripes;
}

namespace {

// Per node: the area-weighted normal of the surface triangles around it (+z where there is none).
std::vector<Eigen::Vector3f> surfaceNormals(const FemBody& body) {
  const TetMesh& mesh = body.model().mesh();
  const int n = mesh.nodeCount();
  std::vector<Eigen::Vector3d> normals(static_cast<size_t>(n), Eigen::Vector3d::Zero());
  for (const Triangle& tri : mesh.surfaceTriangles()) {
    const Eigen::Vector3d a = body.state().position(tri[0]);
    const Eigen::Vector3d area_normal =
        (body.state().position(tri[1]) - a).cross(body.state().position(tri[2]) - a);
    for (int v : tri)
      normals[static_cast<size_t>(v)] += area_normal;
  }
  std::vector<Eigen::Vector3f> unit(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const double len = normals[static_cast<size_t>(i)].norm();
    unit[static_cast<size_t>(i)] = (len > 0 ? Eigen::Vector3d(normals[static_cast<size_t>(i)] / len)
                                            : Eigen::Vector3d::UnitZ())
                                       .cast<float>();
  }
  return unit;
}

// Per node: volume-weighted mean of its tets' von Mises stress.
std::vector<float> nodalStress(const FemBody& body) {
  const TetMesh& mesh = body.model().mesh();
  const std::vector<double> tet_stress = tetVonMises(body);
  std::vector<float> stress(static_cast<size_t>(mesh.nodeCount()));
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    double sum = 0, weight = 0;
    for (int k = mesh.nodeTets().rowBegin(i); k < mesh.nodeTets().rowEnd(i); ++k) {
      const int t = mesh.nodeTets().items[static_cast<size_t>(k)];
      const double v = body.model().tetRestData()[static_cast<size_t>(t)].volume;
      sum += v * tet_stress[static_cast<size_t>(t)];
      weight += v;
    }
    stress[static_cast<size_t>(i)] = static_cast<float>(weight > 0 ? sum / weight : 0.0);
  }
  return stress;
}

// One FEM body: positions (extending the frame's bounds), surface with normals, the rest-shape
// stripes and the nodal stress.
BodyDrawData bodyDrawData(const FemBody& body, Eigen::AlignedBox3d& bounds) {
  const TetMesh& mesh = body.model().mesh();
  const int n = mesh.nodeCount();
  BodyDrawData d;
  d.name = body.name();
  d.positions.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    d.positions[static_cast<size_t>(i)] = body.state().position(i).cast<float>();
    bounds.extend(body.state().position(i));
  }
  for (const Triangle& tri : mesh.surfaceTriangles())
    d.triangles.push_back({tri[0], tri[1], tri[2]});
  d.stripes = restStripes(mesh);
  d.normals = surfaceNormals(body);
  d.stress = nodalStress(body);
  return d;
}

// One hand: its frame (the patch while it holds, else `free_frame`), and a square covering the
// grabbed patch with a margin (or a tenth of the scene); the nodes it holds are marked on their
// body.
HandDrawData handDrawData(const Hand& hand, const std::string& name, const Frame& free_frame,
                          FrameData& frame) {
  HandDrawData d;
  d.name = name;
  d.frame = hand.grabbed() ? hand.frame() : free_frame;
  d.holding = hand.grabbed();
  double reach = 0;
  if (d.holding) {
    const FemBody& body = hand.body();
    for (int i : hand.grabbedNodes())
      reach = std::max(reach, (body.state().position(i) - d.frame.origin).norm());
    for (BodyDrawData& b : frame.bodies) {
      if (b.name == body.name()) {
        b.grabbed_nodes.insert(b.grabbed_nodes.end(), hand.grabbedNodes().begin(),
                               hand.grabbedNodes().end());
      }
    }
  }
  d.plane_half_size = reach > 0
                          ? 1.3 * reach
                          : 0.1 * (frame.bounds.isEmpty() ? 1.0 : frame.bounds.diagonal().norm());
  return d;
}

}  // namespace

void addHand(FrameData& frame, const Hand& hand, const std::string& name, const Frame& free_frame) {
  frame.hands.push_back(handDrawData(hand, name, free_frame, frame));
  frame.bounds.extend(frame.hands.back().frame.origin);
  const Wrench w = hand.wrench();
  frame.wrenches.push_back({name, w.force, w.torque});
}

// The frame as its stages: the header, the FEM bodies, the hands and wrenches, the rigid bodies,
// then the bounds and the stress scale over all of them.
FrameData captureFrame(scene::BuiltScene& scene, double steps_per_second) {
  FemWorld& world = *scene.world;
  FrameData frame;
  frame.title = scene.spec.name;
  frame.time = world.time();
  frame.step = world.stepCount();
  frame.steps_per_second = steps_per_second;
  frame.gravity = world.settings().gravity;
  frame.camera = scene.spec.camera;
  // Floor of the scale: the stress of a 1e-6 strain. Below it the values are round-off (a body
  // at rest shows ~1e-11 Pa), and a scale fitted to them would paint noise.
  double stress_max = 0;
  for (const auto& body : world.bodies())
    stress_max = std::max(stress_max, 1e-6 * body->model().material().youngs_modulus);

  for (const auto& body : world.bodies()) {
    frame.bodies.push_back(bodyDrawData(*body, frame.bounds));
    for (int i : body->model().mesh().surfaceNodes())
      stress_max = std::max(
          stress_max, static_cast<double>(frame.bodies.back().stress[static_cast<size_t>(i)]));
  }
  for (const scene::SceneHand& h : scene.hands)
    addHand(frame, *h.hand, h.spec.name, h.spec.frameAt(world.time()));
  for (scene::NodeSetHandle& s : scene.node_sets) {
    const Wrench w = s.body->groupWrench(s.group, s.wrench_about);
    frame.wrenches.push_back({s.name, w.force, w.torque});
  }
  if (scene.haptics) {
    for (const auto& [name, w] : scene.haptics->toolWrenches())
      frame.wrenches.push_back({name, w.force, w.torque});  // what the tool's device renders
  }
  for (const btRigidBody* rb : world.rigidBodies()) {
    frame.rigids.push_back(rigidDrawData(*rb));
    extendBounds(frame.rigids.back(), frame.bounds);
  }
  if (frame.bounds.isEmpty()) frame.bounds.extend(Eigen::Vector3d::Zero());
  frame.stress_max = niceCeiling(stress_max);
  return frame;
}

}  // namespace torsion::render
