#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "torsion/device/pose_math.h"
#include "torsion/device/scripted_device.h"
#include "torsion/device/wrench_safety.h"

// The safety rules, driven tick by tick with a fake 1 kHz clock.
namespace torsion::device {
namespace {

constexpr double kDt = 0.001;

SafetyInputs healthy() {
  return {true, true, true};
}

// Ticks until the output settles on `desired` (or `ticks` have passed).
void settle(SafetyFilter& f, const Wrench& desired, int ticks = 2000) {
  for (int k = 0; k < ticks; ++k)
    f.apply(desired, healthy(), kDt);
}

TEST(SafetyFilter, FollowsADesiredWrenchWithinLimitsAfterFadingIn) {
  SafetyFilter f(SafetySettings{}, defaultDeviceLimits());
  settle(f, {{3, 0, -4}, {0, 0.5, 0}});
  EXPECT_NEAR(f.output().force.z, -4, 1e-12);
  EXPECT_NEAR(f.output().torque.y, 0.5, 1e-12);
}

TEST(SafetyFilter, ALaterStagesChangeIsHeldToTheRateLimitOfWhatTheDeviceHolds) {
  // A passivity controller proposes a wrench far from the filter's output; follow() keeps the
  // rate limit the last stage: from the last tick's output by at most 0.3 N and 0.03 N m, and
  // the next tick starts from what was written.
  const SafetySettings s;
  SafetyFilter f(s, defaultDeviceLimits());
  settle(f, {{5, 0, 0}, {0, 0, 1}});
  const Wrench held = f.output();
  f.apply({{5, 0, 0}, {0, 0, 1}}, healthy(), kDt);
  const Wrench written = f.follow({{-30, 0, 0}, {0, 0, -3}}, kDt);
  EXPECT_NEAR(norm(written.force - held.force), s.max_force_rate * kDt, 1e-12);
  EXPECT_NEAR(norm(written.torque - held.torque), s.max_torque_rate * kDt, 1e-12);
  EXPECT_NEAR(written.force.x, 5 - s.max_force_rate * kDt, 1e-12);  // toward the proposal
  EXPECT_EQ(f.output().force.x, written.force.x);
  // Next tick: within the rate limit of what was written the proposal is taken as it is.
  f.apply({{5, 0, 0}, {0, 0, 1}}, healthy(), kDt);
  const Wrench small = f.follow({{written.force.x + 0.1, 0, 0}, written.torque}, kDt);
  EXPECT_NEAR(small.force.x, written.force.x + 0.1, 1e-12);
  // And a non-finite proposal is a zero target, approached at the rate limit.
  f.apply({{5, 0, 0}, {0, 0, 1}}, healthy(), kDt);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Wrench zeroed = f.follow({{nan, 0, 0}, small.torque}, kDt);
  EXPECT_TRUE(isFinite(zeroed));
  EXPECT_NEAR(zeroed.force.x, small.force.x - s.max_force_rate * kDt, 1e-12);
}

TEST(SafetyFilter, NeverJumps) {
  const SafetySettings s;
  SafetyFilter f(s, defaultDeviceLimits());
  Wrench previous;
  // A violently alternating request, far beyond the limits.
  for (int k = 0; k < 3000; ++k) {
    const double sign = (k / 7) % 2 ? 1 : -1;
    const Wrench out = f.apply({{sign * 1e6, 0, 0}, {0, 0, -sign * 1e4}}, healthy(), kDt);
    EXPECT_LE(std::abs(out.force.x - previous.force.x), s.max_force_rate * kDt + 1e-9);
    EXPECT_LE(std::abs(out.torque.z - previous.torque.z), s.max_torque_rate * kDt + 1e-9);
    previous = out;
  }
}

TEST(SafetyFilter, SaturatesAtTheDeviceLimits) {
  const DeviceLimits limits = defaultDeviceLimits();
  SafetyFilter f(SafetySettings{}, limits);
  for (int k = 0; k < 5000; ++k) {
    const double a = 0.01 * k;
    const Wrench out =
        f.apply({{1e5 * std::cos(a), 1e5 * std::sin(a), 3e4}, {1e3, -1e3 * std::sin(3 * a), 0}},
                healthy(), kDt);
    EXPECT_LE(norm(out.force), limits.max_force + 1e-9);
    EXPECT_LE(norm(out.torque), limits.max_torque + 1e-9);
  }
}

TEST(SafetyFilter, StaleSimulationOrDeadDeviceFadesToZeroWithinFadeTime) {
  const SafetySettings s;
  const DeviceLimits limits = defaultDeviceLimits();
  for (int cause = 0; cause < 2; ++cause) {
    SafetyFilter f(s, limits);
    settle(f, {{30, 0, 0}, {0, 0, 3}}, 5000);  // at the limits: the longest fade
    ASSERT_NEAR(norm(f.output().force), limits.max_force, 1e-9);
    SafetyInputs sick = healthy();
    (cause == 0 ? sick.simulation_fresh : sick.device_alive) = false;
    const int fade_ticks = static_cast<int>(std::ceil(s.fade_time / kDt));
    double previous = norm(f.output().force);
    for (int k = 0; k < fade_ticks; ++k) {
      const Wrench out = f.apply({{30, 0, 0}, {0, 0, 3}}, sick, kDt);
      EXPECT_LE(norm(out.force), previous + 1e-12);  // monotone: no bump on the way down
      previous = norm(out.force);
    }
    EXPECT_EQ(norm(f.output().force), 0.0) << "cause " << cause;
    EXPECT_EQ(norm(f.output().torque), 0.0) << "cause " << cause;
  }
}

TEST(SafetyFilter, ZeroWhenNothingIsGrabbed) {
  SafetyFilter f(SafetySettings{}, defaultDeviceLimits());
  settle(f, {{10, 0, 0}, {}});
  SafetyInputs released = healthy();
  released.grabbed = false;
  for (int k = 0; k < 200; ++k)
    f.apply({{10, 0, 0}, {}}, released, kDt);
  EXPECT_EQ(norm(f.output().force), 0.0);
}

TEST(SafetyFilter, NanNeverReachesTheOutput) {
  SafetyFilter f(SafetySettings{}, defaultDeviceLimits());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  settle(f, {{5, 0, 0}, {}});
  for (int k = 0; k < 100; ++k) {
    const Wrench out = f.apply({{nan, 1, 2}, {inf, 0, 0}}, healthy(), k % 3 ? kDt : nan);
    EXPECT_TRUE(isFinite(out));
  }
}

TEST(SafetySettings, ValidateNamesTheField) {
  SafetySettings s;
  s.fade_time = 0;
  EXPECT_NE(s.validate().find("fade_time"), std::string::npos);
  EXPECT_TRUE(SafetySettings{}.validate().empty());
}

}  // namespace
}  // namespace torsion::device
