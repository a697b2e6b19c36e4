#include "torsion/device/manual_device.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>

#include "torsion/device/pose_math.h"
#include "torsion/device/scripted_device.h"

namespace torsion::device {
namespace {

// A pose whose seven numbers all encode k: a reader that sees two different values in one pose
// read half of one update and half of another.
Pose poseNumbered(double k) {
  Pose p;
  p.position = {k, k, k};
  p.orientation = {k, k, k, k};
  return p;
}

bool whole(const Pose& p) {
  const double k = p.position.x;
  return p.position.y == k && p.position.z == k && p.orientation.w == k && p.orientation.x == k &&
         p.orientation.y == k && p.orientation.z == k;
}

TEST(ManualDevice, StartsAtTheZeroPoseAliveWithNoButtonAndTheGivenLimits) {
  DeviceLimits limits = defaultDeviceLimits();
  limits.max_force = 12;
  ManualDevice device(limits);
  const DeviceSample s = device.read(0.25);
  EXPECT_TRUE(s.alive);
  EXPECT_EQ(s.time, 0.25);
  EXPECT_EQ(s.buttons, 0u);
  EXPECT_EQ(s.pose.position.x, 0);
  EXPECT_EQ(s.pose.orientation.w, 1);
  EXPECT_EQ(device.limits().max_force, 12);
  EXPECT_EQ(device.name(), "manual");
}

TEST(ManualDevice, ReadsWhatWasSetAndKeepsTheLastWrench) {
  ManualDevice device(defaultDeviceLimits());
  Pose p;
  p.position = {0.01, -0.02, 0.03};
  p.orientation = {0.6, 0.8, 0, 0};
  device.setPose(p);
  device.setButtons(0x1);
  const DeviceSample s = device.read(1.0);
  EXPECT_EQ(s.pose.position.y, -0.02);
  EXPECT_EQ(s.pose.orientation.x, 0.8);
  EXPECT_EQ(s.buttons, 0x1u);
  device.setButtons(0);
  EXPECT_EQ(device.read(2.0).buttons, 0u);
  EXPECT_TRUE(device.read(1e9).alive);  // no operator timeout: the viewer is always there

  Wrench w;
  w.force = {1, 2, 3};
  w.torque = {-0.1, 0, 0.2};
  device.write(w);
  EXPECT_EQ(device.lastWritten().force.z, 3);
  EXPECT_EQ(device.lastWritten().torque.x, -0.1);
}

// The viewer's thread sets pose k then buttons k while the loop's thread reads: every reading
// holds one whole pose, never older than the previous reading, and the buttons of that update
// or the one before (they are set a moment after the pose), always alive. Without a glide, so
// that each reading is a pose as set.
TEST(ManualDevice, AReaderOnAnotherThreadSeesWholePosesInOrder) {
  ManualDevice device(defaultDeviceLimits(), 0.0);
  device.setPose(poseNumbered(0));
  constexpr std::uint32_t kUpdates = 100000;
  std::atomic<bool> done{false};
  std::thread viewer([&] {
    for (std::uint32_t k = 1; k <= kUpdates; ++k) {
      device.setPose(poseNumbered(static_cast<double>(k)));
      device.setButtons(k);
    }
    done = true;
  });
  double newest = 0;
  long reads = 0, torn = 0, older = 0, dead = 0, mismatched = 0;
  for (bool finished = false; !finished;) {
    finished = done.load();  // one more read after the last update
    const DeviceSample s = device.read(static_cast<double>(reads++));
    const auto k = static_cast<std::uint32_t>(s.pose.position.x);
    torn += whole(s.pose) ? 0 : 1;
    older += s.pose.position.x < newest ? 1 : 0;
    dead += s.alive ? 0 : 1;
    mismatched += s.buttons == k || s.buttons + 1 == k ? 0 : 1;
    newest = s.pose.position.x;
  }
  viewer.join();
  EXPECT_EQ(torn, 0) << "of " << reads << " reads";
  EXPECT_EQ(older, 0);
  EXPECT_EQ(dead, 0);
  EXPECT_EQ(mismatched, 0);
  EXPECT_EQ(newest, kUpdates);
  EXPECT_EQ(device.read(0).buttons, kUpdates);
}

// A key press moves the device as a hand would: evenly over the glide time (0.1 s), position
// along the line and orientation along the arc, ending exactly on the pose set; 1 kHz readings
// then move at 1 m/s for a 0.1 m press, a tenth of the reading check's bound. A new pose in the
// middle of a glide starts a new one from where the device is.
TEST(ManualDevice, APoseSetIsReachedEvenlyOverTheGlideTime) {
  ManualDevice device(defaultDeviceLimits());
  EXPECT_EQ(device.read(0.0).pose.position.x, 0);  // the first read is where it was set
  Pose p;
  p.position = {0.1, 0, 0};
  p.orientation = fromRotationVector({0, 0, 0.4});
  device.setPose(p);
  double previous = 0, fastest = 0;
  for (int tick = 1; tick <= 50; ++tick) {
    const DeviceSample s = device.read(tick * 1e-3);
    fastest = std::max(fastest, (s.pose.position.x - previous) / 1e-3);
    previous = s.pose.position.x;
    EXPECT_NEAR(s.pose.position.x, 0.1 * tick / 100.0, 1e-15) << "tick " << tick;
    EXPECT_NEAR(toRotationVector(s.pose.orientation).z, 0.4 * tick / 100.0, 1e-12);
  }
  EXPECT_NEAR(fastest, 1.0, 1e-9);  // m/s
  // Retargeted halfway (at 0.05 m): the new glide starts there and ends on the new pose.
  Pose q = p;
  q.position = {-0.05, 0, 0};
  device.setPose(q);
  EXPECT_NEAR(device.read(0.1).pose.position.x, 0.05 - 0.1 * 0.5, 1e-15);
  const DeviceSample end = device.read(0.2);
  EXPECT_EQ(end.pose.position.x, -0.05);  // exactly
  EXPECT_EQ(device.read(5.0).pose.position.x, -0.05);
}

// The loop's thread writes wrenches while the viewer's thread reads them: each one whole.
TEST(ManualDevice, TheViewerReadsWholeWrenchesWrittenByTheLoop) {
  ManualDevice device(defaultDeviceLimits());
  constexpr int kWrites = 100000;
  std::atomic<bool> done{false};
  std::thread loop([&] {
    for (int k = 1; k <= kWrites; ++k) {
      Wrench w;
      const double v = static_cast<double>(k);
      w.force = {v, v, v};
      w.torque = {v, v, v};
      device.write(w);
    }
    done = true;
  });
  double newest = 0;
  long torn = 0, older = 0;
  while (!done.load()) {
    const Wrench w = device.lastWritten();
    torn += w.force.x == w.force.y && w.force.x == w.force.z && w.force.x == w.torque.x &&
                    w.force.x == w.torque.y && w.force.x == w.torque.z
                ? 0
                : 1;
    older += w.force.x < newest ? 1 : 0;
    newest = w.force.x;
  }
  loop.join();
  EXPECT_EQ(torn, 0);
  EXPECT_EQ(older, 0);
  EXPECT_EQ(device.lastWritten().force.x, kWrites);
}

}  // namespace
}  // namespace torsion::device
