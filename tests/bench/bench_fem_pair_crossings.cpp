// Crossings between FEM bodies over a whole scene (docs/contact.md, "Edge against edge between
// bodies" and "Contact thickness"): after every step, the exact checker
// (analysis/surface_intersections.h) tests the surface triangles of every two FEM bodies whose
// boxes overlap. Settings of the scene's fem_contact can be overridden, so that the same scene
// runs with and without edge-edge pairs or the contact thickness. One JSON line on stdout.
//
//   bench_fem_pair_crossings SCENE [--steps N] [--edge-edge on|off] [--thickness FACTOR]
//
// crossing_steps: steps after which some two bodies' triangles intersect (touching counts);
// crossing_pairs: such triangle pairs summed over the steps; max_pairs: the most in one step.
#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "scene_builder.h"
#include "scene_haptics.h"
#include "scene_parser.h"
#include "torsion/analysis/surface_intersections.h"

int main(int argc, char** argv) {
  using namespace torsion;
  using namespace torsion::scene;
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SCENE [--steps N] [--edge-edge on|off] [--thickness FACTOR]\n",
                 argv[0]);
    return 1;
  }
  Result<SceneSpec> spec = loadScene(argv[1]);
  if (!spec) {
    std::fprintf(stderr, "%s\n", spec.error().message.c_str());
    return 1;
  }
  int steps = spec.value().steps;
  std::optional<BodyContactSettings>& contact = spec.value().fem_contact;
  for (int a = 2; a + 1 < argc; a += 2) {
    if (!std::strcmp(argv[a], "--steps")) steps = std::atoi(argv[a + 1]);
    if (!std::strcmp(argv[a], "--edge-edge") && contact)
      contact->edge_edge = std::strcmp(argv[a + 1], "off") != 0;
    if (!std::strcmp(argv[a], "--thickness") && contact)
      contact->thickness_factor = std::atof(argv[a + 1]);
  }
  const bool edge_edge = contact && contact->edge_edge;
  const double thickness = contact ? contact->thickness_factor : 0;
  Result<std::unique_ptr<BuiltScene>> built = buildScene(std::move(spec.value()), BuildOptions{1});
  if (!built) {
    std::fprintf(stderr, "%s\n", built.error().message.c_str());
    return 1;
  }
  BuiltScene& scene = *built.value();
  const auto& bodies = scene.world->bodies();
  auto box = [](const Eigen::VectorXd& x, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
    const Eigen::Map<const Eigen::Matrix3Xd> points(x.data(), 3, x.size() / 3);
    lo = points.rowwise().minCoeff();
    hi = points.rowwise().maxCoeff();
  };
  int crossing_steps = 0, first = -1, max_pairs = 0;
  long pairs_total = 0;
  for (int k = 1; k <= steps; ++k) {
    Result<WorldStepReport> report = stepScene(scene);
    if (!report || !report.value().ok) {
      std::fprintf(stderr, "step %d failed\n", k);
      return 2;
    }
    int pairs = 0;
    for (size_t i = 0; i < bodies.size(); ++i) {
      for (size_t j = i + 1; j < bodies.size(); ++j) {
        const Eigen::VectorXd& xi = bodies[i]->state().positions;
        const Eigen::VectorXd& xj = bodies[j]->state().positions;
        Eigen::Vector3d lo_i, hi_i, lo_j, hi_j;
        box(xi, lo_i, hi_i);
        box(xj, lo_j, hi_j);
        if ((lo_i.array() > hi_j.array()).any() || (lo_j.array() > hi_i.array()).any()) continue;
        pairs += static_cast<int>(
            findSurfaceIntersections(bodies[i]->model().mesh().surfaceTriangles(), xi,
                                     bodies[j]->model().mesh().surfaceTriangles(), xj)
                .size());
      }
    }
    if (pairs > 0) {
      ++crossing_steps;
      if (first < 0) first = k;
    }
    pairs_total += pairs;
    max_pairs = std::max(max_pairs, pairs);
  }
  std::printf(
      "{\"scene\": \"%s\", \"steps\": %d, \"edge_edge\": %s, \"thickness_factor\": %g, "
      "\"crossing_steps\": %d, \"first_crossing_step\": %d, \"crossing_pairs\": %ld, "
      "\"max_pairs\": %d}\n",
      argv[1], steps, edge_edge ? "true" : "false", thickness, crossing_steps, first, pairs_total,
      max_pairs);
  return 0;
}
