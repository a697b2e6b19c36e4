// The plectoneme scene (demos/scenes/plectoneme.json; docs/contact.md, "Self-contact"): a
// 7951-tet rod, 40 radii long, turned 6 times by its end at a fixed end distance, buckles, loops
// and coils onto itself. Run as `torsion run` runs it, with the exact triangle-triangle check
// (analysis/surface_intersections.h) over the whole surface after every step: the coil must press
// on itself (self-contact active) without any two surface triangles crossing, every self-contact
// solve must converge, and no linearised end gap may go deeper than the gap tolerance.
// Label "physics" (about 40 s in Release).

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "demo_scenes.h"
#include "scene_haptics.h"
#include "torsion/analysis/surface_intersections.h"

namespace torsion::scene {
namespace {

TEST(Plectoneme, TheRodCoilsOntoItselfWithoutAnySurfaceTrianglesCrossingAtAnyStep) {
  std::unique_ptr<BuiltScene> scene = buildDemoScene("plectoneme");
  ASSERT_NE(scene, nullptr);
  FemBody* rod = nullptr;
  for (const auto& b : scene->world->bodies())
    if (b->selfContact() != nullptr) rod = b.get();
  ASSERT_NE(rod, nullptr) << "the scene's rod has self-contact on";
  const double gap_tolerance = rod->selfContact()->gapTolerance();
  const std::vector<Triangle>& surface = rod->model().mesh().surfaceTriangles();

  int steps = 0, unconverged = 0, crossing_steps = 0, first_crossing = -1, contact_steps = 0,
      max_active = 0;
  double deepest_end = 0;
  for (int k = 1; k <= scene->spec.steps; ++k) {
    Result<WorldStepReport> report = stepScene(*scene);
    ASSERT_TRUE(report && report.value().ok)
        << "step " << k << ": " << (report ? report.value().message : report.error().message);
    ++steps;
    const SelfContactStats& s = rod->selfContact()->stats();
    unconverged += s.converged ? 0 : 1;
    contact_steps += s.active > 0 ? 1 : 0;
    max_active = std::max(max_active, s.active);
    deepest_end = std::max(deepest_end, s.max_end_penetration);
    if (!findSurfaceIntersections(surface, rod->state().positions).empty()) {
      ++crossing_steps;
      if (first_crossing < 0) first_crossing = k;
    }
  }
  std::printf(
      "plectoneme: %d steps, self-contact active in %d (at most %d contacts), %d "
      "unconverged, deepest end gap %.3g m (tolerance %.3g), %d steps with crossing "
      "triangles\n",
      steps, contact_steps, max_active, unconverged, deepest_end, gap_tolerance, crossing_steps);
  // The coil presses on itself: the test is about held contact, not a rod that never touches.
  EXPECT_GE(contact_steps, 100);
  EXPECT_GE(max_active, 10);
  EXPECT_EQ(unconverged, 0);
  EXPECT_LE(deepest_end, gap_tolerance);
  EXPECT_EQ(crossing_steps, 0) << "first at step " << first_crossing;
}

}  // namespace
}  // namespace torsion::scene
