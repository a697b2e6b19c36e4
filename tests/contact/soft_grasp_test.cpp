// The scene soft_grasp (demos/scenes/soft_grasp.json; docs/contact.md, "Scene soft_grasp"): two
// soft fingers, each carried by a hand at its back, squeeze a soft block standing on rigid ground
// and lift it 0.3 m. Friction between the FEM bodies alone holds the block up: it must rise with
// the fingers, not slip out.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include "scene_builder.h"
#include "scene_haptics.h"
#include "scene_parser.h"

namespace torsion {
namespace {

Eigen::Vector3d centreOf(const FemBody& body) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    c += body.model().nodeMasses()[static_cast<size_t>(i)] * body.state().position(i);
  return c / body.model().totalMass();
}

TEST(SoftGrasp, ASoftBlockSqueezedBetweenTwoSoftFingersRisesWithThemWithoutSlipping) {
  Result<scene::SceneSpec> spec = scene::loadScene(TORSION_SCENES_DIR "/soft_grasp.json");
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  const int steps = spec.value().steps;
  Result<std::unique_ptr<scene::BuiltScene>> built =
      scene::buildScene(std::move(spec.value()), scene::BuildOptions{1});
  ASSERT_TRUE(built.ok()) << built.error().message;
  scene::BuiltScene& s = *built.value();
  const FemBody* object = s.world->body("object");
  const FemBody* left = s.world->body("left_finger");
  const FemBody* right = s.world->body("right_finger");
  ASSERT_TRUE(object != nullptr && left != nullptr && right != nullptr);
  const Eigen::Vector3d object_start = centreOf(*object);
  // Once squeezed (t = 0.5 s) the block's height relative to the fingers' must stay put.
  double relative_at_squeeze = 0, worst_slip = 0, worst_penetration = 0;
  int unconverged = 0;
  for (int k = 0; k < steps; ++k) {
    Result<WorldStepReport> r = scene::stepScene(s);
    ASSERT_TRUE(r.ok() && r.value().ok) << (r.ok() ? r.value().message : r.error().message);
    const FemContactStats& c = s.world->femSolver().femContact()->stats();
    if (!c.converged) ++unconverged;
    worst_penetration = std::max(worst_penetration, c.max_end_penetration);
    const double fingers = 0.5 * (centreOf(*left).z() + centreOf(*right).z());
    const double relative = centreOf(*object).z() - fingers;
    if (k == 49) relative_at_squeeze = relative;
    if (k > 49) worst_slip = std::max(worst_slip, std::abs(relative - relative_at_squeeze));
  }
  const double rise = centreOf(*object).z() - object_start.z();
  const double fingers_rise = 0.5 * (centreOf(*left).z() + centreOf(*right).z()) - 0.12;
  std::printf(
      "[figures] soft grasp: block rose %.4f m, fingers %.4f m, worst slip of the block against "
      "the fingers after the squeeze %.2e m, unconverged steps %d of %d, worst end penetration "
      "%.2e m\n",
      rise, fingers_rise, worst_slip, unconverged, steps, worst_penetration);
  // The hands lift by 0.3 m; the block hangs between the fingers, sagging with them.
  EXPECT_GT(rise, 0.27);
  EXPECT_LT(worst_slip, 0.01);
  EXPECT_EQ(unconverged, 0);  // the island's convex solve converges from any start
}

}  // namespace
}  // namespace torsion
