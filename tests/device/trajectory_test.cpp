#include "torsion/device/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>

#include "torsion/device/pose_math.h"

namespace torsion::device {
namespace {

double angleAbout(const Quat& q, const Vec3& axis) {
  return dot(toRotationVector(q), axis);
}

TEST(Trajectory, SegmentsIntegrateConstantVelocities) {
  const auto frames =
      keyframesFromSegments(Pose{}, {{2.0, {0.5, 0, 0}, {0, 0, 0}}, {4.0, {0, 0, 0}, {0, 0, 1.0}}});
  const Trajectory t(frames, {});
  EXPECT_NEAR(t.poseAt(1.0).position.x, 0.5, 1e-12);
  EXPECT_NEAR(t.poseAt(2.0).position.x, 1.0, 1e-12);
  // 4 rad about z, beyond pi: split so the interpolation follows the motion, not the short arc.
  EXPECT_NEAR(angleAbout(t.poseAt(3.0).orientation, {0, 0, 1}), 1.0, 1e-9);
  const Vec3 e = rotate(t.poseAt(6.0).orientation, {1, 0, 0});
  EXPECT_NEAR(e.x, std::cos(4.0), 1e-9);
  EXPECT_NEAR(e.y, std::sin(4.0), 1e-9);
  EXPECT_NEAR(t.poseAt(100.0).position.x, 1.0, 1e-12);  // held after the end
  EXPECT_DOUBLE_EQ(t.duration(), 6.0);
}

TEST(Trajectory, ButtonsAreHeldFromTheirEvent) {
  const Trajectory t({{0, Pose{}}}, {{0.0, 1u}, {0.5, 0u}, {2.0, 2u}});
  EXPECT_EQ(t.buttonsAt(0.2), 1u);
  EXPECT_EQ(t.buttonsAt(1.0), 0u);
  EXPECT_EQ(t.buttonsAt(3.0), 2u);
}

TEST(Trajectory, Figure67AssetHasTheReportsSixPhases) {
  Loaded<Trajectory> t = loadTrajectory(TORSION_TRAJECTORIES_DIR "/figure_6_7.json");
  ASSERT_TRUE(t) << t.error;
  const Trajectory& f = *t.value;
  // Mid-phase (t = 10 + 20 k): each phase moves along its own axis only.
  EXPECT_NEAR(angleAbout(f.poseAt(10).orientation, {1, 0, 0}), 0.3, 1e-9);
  EXPECT_NEAR(f.poseAt(30).position.x, 0.05, 1e-9);
  EXPECT_NEAR(f.poseAt(50).position.z, 0.05, 1e-9);
  EXPECT_NEAR(angleAbout(f.poseAt(70).orientation, {0, 0, 1}), 0.5, 1e-9);
  EXPECT_NEAR(angleAbout(f.poseAt(90).orientation, {0, 1, 0}), 0.3, 1e-9);
  EXPECT_NEAR(f.poseAt(110).position.y, 0.05, 1e-9);
  // And back home between phases.
  for (double time : {20.0, 40.0, 60.0, 80.0, 100.0, 120.0}) {
    EXPECT_NEAR(norm(f.poseAt(time).position), 0, 1e-9) << time;
    EXPECT_NEAR(norm(toRotationVector(f.poseAt(time).orientation)), 0, 1e-9) << time;
  }
  EXPECT_EQ(f.buttonsAt(0.05), 1u);    // button 1: grab
  EXPECT_EQ(f.buttonsAt(120.55), 2u);  // button 2: release
}

TEST(Trajectory, BadFilesNameTheKey) {
  auto expectError = [](const char* text, const char* needle) {
    Loaded<Trajectory> t = parseTrajectory(text, "bad.json");
    ASSERT_FALSE(t) << text;
    EXPECT_NE(t.error.find(needle), std::string::npos) << t.error;
    EXPECT_EQ(t.error.rfind("bad.json", 0), 0u) << t.error;
  };
  expectError("{", "not valid JSON");
  expectError("{}", "'segments' / 'keyframes'");
  expectError(R"({"segments": [{"duration": -1}]})", "segments[0].duration");
  expectError(R"({"segments": [{"duration": 1, "linear_velocity": [1, 2]}]})",
              "segments[0].linear_velocity");
  expectError(R"({"keyframes": [{"time": 1}, {"time": 1}]})", "keyframes[1].time");
  expectError(R"({"keyframes": [{"time": 0}], "buttons": [{"time": 0, "held": [0]}]})",
              "buttons[0].held");
}

TEST(Trajectory, NumbersBeyondADoubleAndDuplicateKeysAreErrorsNotAbortsOrSilentChoices) {
  // nlohmann throws out_of_range (not parse_error) on 1e400, and keeps the last of two equal
  // keys: both must come back as errors naming the place.
  Loaded<Trajectory> big = parseTrajectory(R"({"segments": [{"duration": 1e400}]})", "big.json");
  ASSERT_FALSE(big);
  EXPECT_EQ(big.error, "big.json:1:28: not valid JSON: number out of range of a double: 1e400");
  Loaded<Trajectory> twice =
      parseTrajectory(R"({"segments": [{"duration": 1, "duration": 2}]})", "twice.json");
  ASSERT_FALSE(twice);
  EXPECT_EQ(twice.error,
            "twice.json: not valid JSON: duplicate key 'duration' in object 'segments[0]'");
}

TEST(Trajectory, OnlyRegularFilesAreRead) {
  // A FIFO would block the reader forever and /dev/zero never ends: both refused at once.
  Loaded<Trajectory> zero = loadTrajectory("/dev/zero");
  ASSERT_FALSE(zero);
  EXPECT_EQ(zero.error, "/dev/zero: cannot open: is a character device, not a regular file");
}

}  // namespace
}  // namespace torsion::device
