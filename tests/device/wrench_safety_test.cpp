#include "torsion/device/wrench_safety.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace torsion::device {
namespace {

DeviceLimits limits() {
  DeviceLimits l;
  l.max_force = 10;
  l.max_torque = 1;
  return l;
}

TEST(WrenchSafety, WithinLimitsPassesUnchanged) {
  const Wrench w{{1, 2, 3}, {0.1, 0.2, 0.3}};
  const Wrench s = saturate(w, limits());
  EXPECT_EQ(s.force.y, 2);
  EXPECT_EQ(s.torque.z, 0.3);
}

TEST(WrenchSafety, SaturationKeepsDirectionAndCapsNorm) {
  const Wrench s = saturate({{30, 40, 0}, {0, 0, -5}}, limits());
  EXPECT_NEAR(std::hypot(s.force.x, s.force.y, s.force.z), 10.0, 1e-12);
  EXPECT_NEAR(s.force.x / s.force.y, 0.75, 1e-12);
  EXPECT_NEAR(s.torque.z, -1.0, 1e-12);
}

TEST(WrenchSafety, NonFiniteBecomesZero) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Wrench s = saturate({{1, nan, 0}, {0, 0, 0.5}}, limits());
  EXPECT_FALSE(isFinite(Wrench{{1, nan, 0}, {}}));
  EXPECT_EQ(s.force.x, 0);
  EXPECT_EQ(s.torque.z, 0);
  EXPECT_TRUE(isFinite(s));
}

}  // namespace
}  // namespace torsion::device
