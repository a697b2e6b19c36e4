// A structured box mesh must not bias the physics: the cantilever of the beam tests (40 x 4 x 4
// cells, mirror-symmetric about its vertical mid-plane y = 1/2 with the alternating split of
// box_mesh.h) under a vertical load must deflect vertically only. With every cell split the same
// way (the split before the alternating one) the tip also moved sideways: by 7.0 % of its vertical
// deflection in statics, by up to 10.9 % of the vertical swing in 2.5 s of free vibration.
#include <gtest/gtest.h>

#include <cstdio>

#include "clamped_beam.h"

namespace torsion {
namespace {

using test::BeamSpec;
using test::ClampedBeam;

TEST(BoxMeshSymmetry, VerticallyLoadedCantileverDoesNotBendSideways) {
  ClampedBeam beam(BeamSpec{});  // 4 cells across, 3840 tets
  const StepReport r = beam.solveStatics();
  ASSERT_FALSE(isFatal(r.health)) << r.message;
  const Eigen::Vector3d tip = beam.tipDisplacement();
  std::printf("static tip displacement (%.3e, %.3e, %.3e) m, sideways / vertical %.2e\n", tip.x(),
              tip.y(), tip.z(), std::abs(tip.y() / tip.z()));
  EXPECT_GT(-tip.z(), 0.5 * test::eulerBernoulliTip(beam.spec()));  // it did bend
  EXPECT_LT(std::abs(tip.y()), 0.005 * std::abs(tip.z()));
}

// Released at rest under gravity, the beam swings about its static deflection (first bending
// mode about 1.6 Hz: four periods in 2.5 s). Sideways motion stays below 0.5 % of the vertical
// swing at every step.
TEST(BoxMeshSymmetry, FreeVibrationStaysInTheVerticalPlane) {
  BeamSpec spec;
  spec.solver.time_step = 0.01;
  ClampedBeam beam(spec);
  double max_vertical = 0, max_sideways = 0;
  for (int k = 0; k < 250; ++k) {
    const StepReport r = beam.step();
    ASSERT_FALSE(isFatal(r.health)) << r.message;
    const Eigen::Vector3d tip = beam.tipDisplacement();
    max_vertical = std::max(max_vertical, std::abs(tip.z()));
    max_sideways = std::max(max_sideways, std::abs(tip.y()));
  }
  std::printf("2.5 s of free vibration: max |tip z| %.3e m, max |tip y| %.3e m (ratio %.2e)\n",
              max_vertical, max_sideways, max_sideways / max_vertical);
  EXPECT_GT(max_vertical,
            test::eulerBernoulliTip(beam.spec()));  // it swung past the static deflection
  EXPECT_LT(max_sideways, 0.005 * max_vertical);
}

}  // namespace
}  // namespace torsion
