// The SpaceMouse's readings are velocities; the integrator turns them into a pose. These cases
// check it against the closed forms of constant twists (no libspnav involved). Tolerances: the
// motions are linear in time or a rotation about one fixed axis, which the integrator composes
// exactly, so only round-off (1e-12) separates it from the closed form.
#include "torsion/device/spacemouse_integrator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "torsion/device/pose_math.h"
#include "torsion/device/spacemouse_device.h"

namespace torsion::device {
namespace {

SpaceMouseReading translate(int x, int y, int z) {
  SpaceMouseReading r;
  r.translation[0] = x;
  r.translation[1] = y;
  r.translation[2] = z;
  return r;
}

SpaceMouseReading turn(int rx, int ry, int rz) {
  SpaceMouseReading r;
  r.rotation[0] = rx;
  r.rotation[1] = ry;
  r.rotation[2] = rz;
  return r;
}

// Ticks the integrator every `period` from t0 to t1 (inclusive of t1).
void run(SpaceMouseIntegrator& m, double t0, double t1, double period) {
  const int n = static_cast<int>(std::lround((t1 - t0) / period));
  for (int k = 0; k <= n; ++k)
    m.advance(t0 + k * period);
}

TEST(SpaceMouseIntegrator, FullDeflectionMovesAtMaxSpeed) {
  SpaceMouseSettings s;
  s.max_linear_speed = 0.1;
  SpaceMouseIntegrator m(s);
  m.setReading(translate(350, 0, -350));
  run(m, 0, 0.5, 0.001);
  EXPECT_NEAR(m.pose().position.x, 0.05, 1e-12);
  EXPECT_NEAR(m.pose().position.y, 0, 1e-15);
  EXPECT_NEAR(m.pose().position.z, -0.05, 1e-12);
  EXPECT_NEAR(m.pose().orientation.w, 1, 1e-15);  // no rotation asked
}

TEST(SpaceMouseIntegrator, DeadZoneHoldsStillAndSpeedRisesFromItsEdge) {
  SpaceMouseSettings s;  // dead zone 8 counts, full scale 350
  SpaceMouseIntegrator rest(s);
  rest.setReading(translate(8, -8, 5));  // sensor noise of a cap at rest
  run(rest, 0, 1, 0.001);
  EXPECT_EQ(rest.pose().position.x, 0);
  EXPECT_EQ(rest.pose().position.y, 0);
  EXPECT_EQ(rest.pose().position.z, 0);

  SpaceMouseIntegrator half(s);
  half.setReading(translate(0, 179, 0));  // (179 - 8) / (350 - 8) = 0.5 of full speed
  run(half, 0, 1, 0.001);
  EXPECT_NEAR(half.pose().position.y, 0.5 * s.max_linear_speed, 1e-12);
}

TEST(SpaceMouseIntegrator, TwistTurnsAboutTheFixedAxisAtItsRate) {
  SpaceMouseSettings s;
  s.max_angular_speed = 1.0;
  SpaceMouseIntegrator m(s);
  m.setReading(turn(0, 0, 400));  // beyond full scale: clamped to full speed
  run(m, 0, 1.2, 0.001);
  const Vec3 theta = toRotationVector(m.pose().orientation);
  EXPECT_NEAR(theta.z, 1.2, 1e-12);
  EXPECT_NEAR(theta.x, 0, 1e-12);
  EXPECT_NEAR(norm(m.pose().position), 0, 1e-15);
  // The other way round, as long: back to the identity.
  m.setReading(turn(0, 0, -350));
  run(m, 1.2, 2.4, 0.001);
  EXPECT_NEAR(norm(toRotationVector(m.pose().orientation)), 0, 1e-12);
}

TEST(SpaceMouseIntegrator, PoseDoesNotDependOnTheTickRate) {
  SpaceMouseSettings s;
  SpaceMouseIntegrator fast(s), slow(s);
  const SpaceMouseReading r = [] {
    SpaceMouseReading x = translate(100, -200, 300);
    x.rotation[1] = 250;
    return x;
  }();
  fast.setReading(r);
  slow.setReading(r);
  run(fast, 0, 0.4, 0.001);
  run(slow, 0, 0.4, 0.02);
  EXPECT_NEAR(fast.pose().position.x, slow.pose().position.x, 1e-12);
  EXPECT_NEAR(fast.pose().position.z, slow.pose().position.z, 1e-12);
  const Vec3 a = toRotationVector(fast.pose().orientation);
  const Vec3 b = toRotationVector(slow.pose().orientation);
  EXPECT_NEAR(a.y, b.y, 1e-12);
}

TEST(SpaceMouseIntegrator, WorkspaceClampsWithoutWindUp) {
  SpaceMouseSettings s;  // 0.1 m/s, box +-0.2 m
  SpaceMouseIntegrator m(s);
  m.setReading(translate(350, 0, 0));
  run(m, 0, 5, 0.001);  // 0.5 m asked
  EXPECT_DOUBLE_EQ(m.pose().position.x, 0.2);
  // Pulling back moves away from the wall at once: nothing accumulated beyond it.
  m.setReading(translate(-350, 0, 0));
  run(m, 5, 5.5, 0.001);
  EXPECT_NEAR(m.pose().position.x, 0.15, 1e-12);
}

TEST(SpaceMouseIntegrator, FirstReadSetsTheClockAndLongGapsAreCapped) {
  SpaceMouseSettings s;  // max_step 0.05 s
  SpaceMouseIntegrator m(s);
  m.setReading(translate(350, 0, 0));
  m.advance(100.0);  // the loop's clock may start anywhere: no motion yet
  EXPECT_EQ(m.pose().position.x, 0);
  m.advance(103.0);  // a 3 s stall integrates only max_step, not a 0.3 m jump
  EXPECT_NEAR(m.pose().position.x, 0.05 * 0.1, 1e-12);
}

TEST(SpaceMouseSettings, ValidateNamesTheField) {
  SpaceMouseSettings s;
  EXPECT_EQ(s.validate(), "");
  s.dead_zone = 400;
  EXPECT_NE(s.validate().find("dead_zone"), std::string::npos);
  s = {};
  s.max_linear_speed = -1;
  EXPECT_NE(s.validate().find("max_linear_speed"), std::string::npos);
}

// Here no spacenavd runs: opening must fail with a message that says what is missing, whether
// the build has libspnav (no daemon) or not (no library). Skipped where a daemon's socket exists.
TEST(SpaceMouseDevice, WithoutDaemonTheErrorSaysWhatIsMissing) {
  if (std::FILE* f = std::fopen("/var/run/spnav.sock", "r")) {
    std::fclose(f);
    GTEST_SKIP() << "a spacenavd socket exists on this machine";
  }
  Loaded<std::unique_ptr<HapticDevice>> device = openSpaceMouse(SpaceMouseSettings{});
  ASSERT_FALSE(device);
  if (spaceMouseSupported()) {
    EXPECT_NE(device.error.find("spacenavd"), std::string::npos) << device.error;
  } else {
    EXPECT_NE(device.error.find("libspnav"), std::string::npos) << device.error;
  }
}

}  // namespace
}  // namespace torsion::device
