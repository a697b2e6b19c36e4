#include "torsion/device/haptic_loop.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <vector>

#include "stand_in_simulation.h"
#include "torsion/device/pose_math.h"
#include "torsion/device/scripted_device.h"

// The loop driven by a fake 1 kHz clock (tick(now)), with a stand-in simulation that answers
// every `sim_every` ticks with a spring about the grab pose.
namespace torsion::device {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace haptic_loop_test {

constexpr double kDt = 0.001;

struct SpringSimulation {
  double stiffness = 200;  // N/m
  std::uint64_t step = 0;
  bool with_stiffness = true;  // publish K_h (the loop then predicts between steps)
  void answer(HapticLoop& loop) {
    HandCommand c;
    loop.commands().read(c);
    SimulationWrench w = answerTo(c, ++step);
    w.command_time = c.time;
    w.wrench.force = -stiffness * c.pose.position;
    for (int k = 0; k < 3 && with_stiffness; ++k)
      w.stiffness[7 * k] = -stiffness;
    loop.wrenches().write(w);
  }
};

Trajectory pushAlongX(double speed) {
  // Button 1 at once, then a push along x at `speed` m/s for 1 s, then held.
  return Trajectory({{0, Pose{}}, {1, Pose{{speed, 0, 0}, {}}}}, {{0, 1u}, {0.01, 0u}});
}

TEST(HapticLoop, ButtonsGrabAndReleaseAsInTheReport) {
  ScriptedDevice device(Trajectory({{0, Pose{}}}, {{0, 0u}, {0.1, 1u}, {0.2, 0u}, {0.3, 2u}}),
                        defaultDeviceLimits(), "buttons");
  HapticLoop loop(device, HapticLoopSettings{});
  HandCommand c;
  loop.tick(0.0);
  EXPECT_FALSE(loop.forceEnabled());
  for (int k = 1; k <= 150; ++k)
    loop.tick(k * kDt);
  loop.commands().read(c);
  EXPECT_EQ(c.grab_requests, 1u);  // held for 100 ticks: one press
  EXPECT_EQ(c.release_requests, 0u);
  EXPECT_TRUE(loop.forceEnabled());
  for (int k = 151; k <= 400; ++k)
    loop.tick(k * kDt);
  loop.commands().read(c);
  EXPECT_EQ(c.release_requests, 1u);
  EXPECT_FALSE(loop.forceEnabled());
}

TEST(HapticLoop, LocalModelAndDamperBetweenSteps) {
  SimulationWrench sim;
  sim.pose = Pose{{0.01, 0, 0}, {}};
  sim.wrench.force = {-2, 0, 0};
  sim.stiffness[0] = -200;        // dFx/dx
  sim.stiffness[6 * 5 + 5] = -4;  // dTz/dthetaz
  const double still[6] = {};
  const Pose moved{{0.02, 0, 0}, fromRotationVector({0, 0, 0.1})};
  const Wrench w = renderLocalModel(sim, moved, still, CouplingDamper{});
  EXPECT_NEAR(w.force.x, -4, 1e-12);  // -2 N - 200 N/m * 0.01 m
  EXPECT_NEAR(w.torque.z, -0.4, 1e-12);
  const double moving[6] = {0.5, 0, 0, 0, 0, 0};
  const Wrench d = renderLocalModel(sim, sim.pose, moving, CouplingDamper{3, 0});
  EXPECT_NEAR(d.force.x, -2 - 1.5, 1e-12);  // the damper opposes the velocity
}

TEST(StepBlend, ANewStepComesInThroughAFirstOrderLowPassAndTheStaticWrenchIsTheModels) {
  // The model at the hand's pose jumps by 1 N m (a new step); rendered, model + offset rises
  // from the old value to the new one as 1 - exp(-t / tau), tau = 1 / (2 pi 5 Hz) = 31.8 ms.
  StepBlend blend(5);
  const double tau = 1 / (2 * M_PI * 5);
  blend.update(Wrench{{}, {0, 0, 1}}, kDt);
  EXPECT_NEAR(blend.offset().torque.z, -std::exp(-kDt / tau), 1e-12);  // one tick's worth in
  for (int k = 1; k < 32; ++k)
    blend.update(Wrench{}, kDt);
  EXPECT_NEAR(1 + blend.offset().torque.z, 1 - std::exp(-0.032 / tau), 1e-12);  // 63 % in
  for (int k = 0; k < 1000; ++k)
    blend.update(Wrench{}, kDt);
  EXPECT_LT(std::abs(blend.offset().torque.z), 1e-12);  // at rest: the model's wrench exactly
  blend.update(Wrench{{0, 0, std::nan("")}, {}}, kDt);  // never NaN
  EXPECT_EQ(blend.offset().force.z, 0.0);
  blend.update(Wrench{{2, 0, 0}, {}}, kDt);
  blend.reset();  // a new grab starts from the model
  EXPECT_EQ(blend.offset().force.x, 0.0);
  StepBlend off;  // 0 Hz: off
  off.update(Wrench{{2, 0, 0}, {}}, kDt);
  EXPECT_FALSE(off.enabled());
  EXPECT_EQ(off.offset().force.x, 0.0);
  HapticLoopSettings settings;
  settings.step_blend_hz = -1;
  EXPECT_EQ(settings.validate(), "step_blend_hz must be non-negative (Hz)");
}

TEST(HapticLoop, ThePredictionFromTheLocalStiffnessIsBoundedByTheDeviceLimits) {
  SimulationWrench sim;
  sim.wrench.force = {-2, 0, 0};
  sim.stiffness[0] = -200;        // dFx/dx, N/m
  sim.stiffness[6 * 5 + 5] = -4;  // dTz/dthetaz, N m/rad
  DeviceLimits limits;
  limits.max_force = 10;
  limits.max_torque = 1;
  const double still[6] = {};
  // 1 m and 1 rad away: unbounded the prediction is -200 N and -4 N m.
  const Pose far{{1, 0, 0}, fromRotationVector({0, 0, 1})};
  const Wrench w = renderLocalModel(sim, far, still, CouplingDamper{}, &limits);
  EXPECT_NEAR(w.force.x, -2 - 10, 1e-12);  // the simulated wrench plus the bounded prediction
  EXPECT_NEAR(w.torque.z, -1, 1e-12);
  // Near the simulated pose the bound changes nothing.
  const Pose near{{0.01, 0, 0}, fromRotationVector({0, 0, 0.1})};
  const Wrench n = renderLocalModel(sim, near, still, CouplingDamper{}, &limits);
  EXPECT_NEAR(n.force.x, -4, 1e-12);
  EXPECT_NEAR(n.torque.z, -0.4, 1e-12);
}

TEST(HapticLoop, InformationAgeIsThePoseAgeWhenPredictingAndTheStepsPoseAgeWhenNot) {
  // A simulation answering every 10 ticks with the command of the tick it answered: without
  // K_h the rendered wrench is that pose's, 0-9 ms old and growing through the step; with K_h
  // the loop renders from this tick's pose: age 0 (the scripted device reads at the tick).
  for (bool with_stiffness : {false, true}) {
    SCOPED_TRACE(with_stiffness);
    ScriptedDevice device(pushAlongX(0.05), defaultDeviceLimits(), "push");
    HapticLoopSettings settings;
    settings.log_capacity = 400;
    HapticLoop loop(device, settings);
    SpringSimulation sim;
    sim.with_stiffness = with_stiffness;
    for (int k = 0; k < 400; ++k) {
      loop.tick(k * kDt);
      if (k % 10 == 0) sim.answer(loop);
    }
    double largest = 0;
    for (const LoopLogRow& r : loop.log()) {
      if (r.sim_step == 0) continue;
      largest = std::max(largest, r.information_age);
      if (with_stiffness) {
        EXPECT_EQ(r.information_age, 0) << r.tick;
      } else {
        // The wrench arrived after the tick of its command: since-arrival is 1 ms younger.
        EXPECT_NEAR(r.information_age, r.wrench_age + kDt, 1e-9) << r.tick;
      }
    }
    if (!with_stiffness) {
      EXPECT_NEAR(largest, 0.010, 1e-9);
    }
  }
}

TEST(HapticLoop, ForceOpposesThePushAndTracksTheSimulation) {
  ScriptedDevice device(pushAlongX(0.05), defaultDeviceLimits(), "push");
  HapticLoop loop(device, HapticLoopSettings{});
  SpringSimulation sim;
  for (int k = 0; k <= 1500; ++k) {
    loop.tick(k * kDt);
    if (k % 10 == 0) sim.answer(loop);  // a 100 Hz simulation
  }
  EXPECT_NEAR(device.lastWritten().force.x, -200 * 0.05, 1e-6);
  EXPECT_EQ(loop.stats().nonfinite, 0u);
}

TEST(HapticLoop, StalledSimulationFadesWithinTheSetTime) {
  ScriptedDevice device(pushAlongX(0.05), defaultDeviceLimits(), "stall");
  HapticLoopSettings settings;
  HapticLoop loop(device, settings);
  SpringSimulation sim;
  int k = 0;
  for (; k <= 1500; ++k) {
    loop.tick(k * kDt);
    if (k % 10 == 0) sim.answer(loop);
  }
  ASSERT_GT(norm(device.lastWritten().force), 5.0);
  const double stall_time = (k - 1) * kDt;  // the last answer came at or before this
  const double deadline = stall_time + settings.safety.stale_after + settings.safety.fade_time;
  for (; k * kDt <= deadline + 1e-9; ++k)
    loop.tick(k * kDt);
  EXPECT_EQ(norm(device.lastWritten().force), 0.0);
  EXPECT_EQ(norm(device.lastWritten().torque), 0.0);
}

TEST(HapticLoop, DeadDeviceGetsZero) {
  ScriptedDevice device(pushAlongX(0.05), defaultDeviceLimits(), "dies");
  device.dieAt(1.2);
  HapticLoopSettings settings;
  HapticLoop loop(device, settings);
  SpringSimulation sim;
  for (int k = 0; k * kDt <= 1.2 + settings.safety.fade_time + 1e-9; ++k) {
    loop.tick(k * kDt);
    sim.answer(loop);  // the simulation keeps going; the device is what died
  }
  EXPECT_EQ(norm(device.lastWritten().force), 0.0);
}

TEST(HapticLoop, NothingPublishedOrReleasedGivesZero) {
  ScriptedDevice device(pushAlongX(0.05), defaultDeviceLimits(), "quiet");
  HapticLoop loop(device, HapticLoopSettings{});
  for (int k = 0; k <= 500; ++k)
    loop.tick(k * kDt);
  EXPECT_EQ(norm(device.lastWritten().force), 0.0);
}

TEST(HapticLoop, ViolentMotionStaysSaturatedAndFinite) {
  // 2 m in 10 ms against a stiff spring: the raw request is kilonewtons.
  ScriptedDevice device(
      Trajectory({{0, Pose{}}, {0.01, Pose{{2, 0, 0}, {}}}, {0.02, Pose{}}}, {{0, 1u}}),
      defaultDeviceLimits(), "violent");
  HapticLoopSettings settings;
  settings.damper = {50, 1};
  HapticLoop loop(device, settings);
  SpringSimulation sim;
  sim.stiffness = 1e5;
  for (int k = 0; k <= 1000; ++k) {
    loop.tick(k * kDt);
    sim.answer(loop);
    EXPECT_LE(norm(device.lastWritten().force), defaultDeviceLimits().max_force + 1e-9);
    EXPECT_TRUE(isFinite(device.lastWritten()));
  }
}

TEST(HapticLoop, LogReplaysAsTheSameMotion) {
  const Trajectory script({{0, Pose{}},
                           {0.2, Pose{{0.01, 0.02, 0}, fromRotationVector({0, 0.3, 0})}},
                           {0.4, Pose{{0, 0.03, 0.01}, {}}}},
                          {{0, 1u}, {0.1, 0u}});
  ScriptedDevice device(script, defaultDeviceLimits(), "record");
  HapticLoopSettings settings;
  settings.log_capacity = 1000;
  HapticLoop loop(device, settings);
  for (int k = 0; k <= 400; ++k)
    loop.tick(5.0 + k * kDt);  // any clock origin
  const std::string path = ::testing::TempDir() + "haptic_loop_log.csv";
  ASSERT_TRUE(loop.writeLog(path));
  Loaded<Trajectory> replayed = loadRecordedTrajectory(path);
  ASSERT_TRUE(replayed) << replayed.error;
  ScriptedDevice replay(*replayed.value, defaultDeviceLimits(), "replay");
  for (double t : {0.0, 0.05, 0.15, 0.2, 0.333, 0.4}) {
    const DeviceSample a = replay.read(t);  // the first read starts the replay at 0
    const Pose b = script.poseAt(t);
    EXPECT_NEAR(norm(a.pose.position - b.position), 0, 1e-6) << t;
    EXPECT_NEAR(norm(toRotationVector(a.pose.orientation * conjugate(b.orientation))), 0, 1e-6);
    EXPECT_EQ(a.buttons, script.buttonsAt(t)) << t;
  }
  std::remove(path.c_str());
}

// A device whose readings from the `from`-th through the `to`-th have their position replaced by
// `glitch` (a corrupted reading, as a packet or a driver may deliver).
class GlitchingDevice : public HapticDevice {
 public:
  GlitchingDevice(HapticDevice& inner, long from, long to, const Vec3& glitch)
      : inner_(inner), from_(from), to_(to), glitch_(glitch) {}
  std::string name() const override { return "glitching"; }
  DeviceLimits limits() const override { return inner_.limits(); }
  DeviceSample read(double time) override {
    DeviceSample s = inner_.read(time);
    ++reads_;
    if (reads_ >= from_ && reads_ <= to_) s.pose.position = glitch_;
    return s;
  }
  void write(const Wrench& wrench) override {
    inner_.write(wrench);
    written_.push_back(wrench);
  }
  /// Every wrench written, in order.
  const std::vector<Wrench>& written() const { return written_; }

 private:
  HapticDevice& inner_;
  long from_, to_;
  Vec3 glitch_;
  long reads_ = 0;
  std::vector<Wrench> written_;
};

struct PushRun {
  std::vector<Wrench> written;  // written to the device, one per tick
  double max_port_energy = 0;
  std::uint64_t refused = 0;
};

// The push into the 200 N/m spring (100 Hz simulation) for 1.5 s; readings `from`-`to` (1-based)
// are glitches at `glitch` (none when from > to).
PushRun pushWithGlitch(long from, long to, const Vec3& glitch) {
  ScriptedDevice scripted(pushAlongX(0.05), defaultDeviceLimits(), "push");
  GlitchingDevice device(scripted, from, to, glitch);
  HapticLoop loop(device, HapticLoopSettings{});
  SpringSimulation sim;
  PushRun run;
  for (int k = 0; k <= 1500; ++k) {
    loop.tick(k * kDt);
    if (k % 10 == 0) sim.answer(loop);
  }
  run.written = device.written();  // what the device was given, tick by tick
  run.max_port_energy = loop.stats().max_port_energy;
  run.refused = loop.stats().refused;
  return run;
}

TEST(HapticLoop, ARefusedReadingEntersNoStateAndTheWrenchGoesOnAsWithoutIt) {
  // One reading at x = 1e7 m in the middle of the push (tick 505, between two simulation steps,
  // the hand at 25 mm feeling 5 N). Booked, it would be megajoules of port energy that the
  // passivity controller then takes back by pinning the output at the device's limit.
  const PushRun clean = pushWithGlitch(1, 0, {});
  const PushRun glitched = pushWithGlitch(506, 506, {1e7, 0, 0});
  EXPECT_EQ(clean.refused, 0u);
  EXPECT_EQ(glitched.refused, 1u);
  // The refused tick's rendering is at the pose held from the tick before: 0.05 m/s x 1 ms x
  // 200 N/m = 0.01 N off; twice that allowed. Every other tick renders the same poses.
  const double rate_step = HapticLoopSettings{}.safety.max_force_rate * kDt;
  for (size_t k = 0; k < clean.written.size(); ++k) {
    EXPECT_LE(norm(glitched.written[k].force - clean.written[k].force), 0.02) << "tick " << k;
    if (k > 0) {
      EXPECT_LE(norm(glitched.written[k].force - glitched.written[k - 1].force),
                rate_step * (1 + 1e-9))
          << "tick " << k;
    }
  }
  // The observer books the motion across the refused tick at the next accepted one, against the
  // wrench held meanwhile: 0.01 N x 0.05 mm = 5e-7 J from the clean run's booking at most.
  EXPECT_LE(glitched.max_port_energy, clean.max_port_energy + 1e-6);
}

TEST(HapticLoop, ADeviceThatKeepsSendingNonsenseIsDeadAfterTheHoldTimeAndItsForceFades) {
  // From 1 s on every reading is at x = 1e7 m: held for reading.hold_time, then the device is
  // dead and the output shrinks to zero within fade_time, as for a device that stops answering.
  const HapticLoopSettings settings;
  const PushRun run = pushWithGlitch(1001, 1000000, {1e7, 0, 0});
  ASSERT_GT(norm(run.written[999].force), 4.0);  // pushing into the spring before
  // Dead at the first tick past the hold time, then at most fade_time to zero.
  const double zero_by = 1.0 + settings.reading.hold_time + kDt + settings.safety.fade_time;
  for (size_t k = 0; k < run.written.size(); ++k) {
    if (static_cast<double>(k) * kDt > zero_by + 1e-9) {
      EXPECT_EQ(norm(run.written[k].force), 0.0) << "tick " << k;
      EXPECT_EQ(norm(run.written[k].torque), 0.0) << "tick " << k;
    }
  }
  EXPECT_EQ(run.refused, 501u);  // ticks 1000-1500 (reads 1001-1501)
  EXPECT_LE(run.max_port_energy, 1e-6);
}

TEST(ReadingCheck, RefusesWhatIsNotAPoseOrMovesFasterThanAHand) {
  const ReadingCheck check;
  EXPECT_TRUE(isPlausiblePose(Pose{{0.1, -0.2, 0.05}, fromRotationVector({0, 0, 1})}, check));
  EXPECT_FALSE(isPlausiblePose(Pose{{1e7, 0, 0}, {}}, check));
  EXPECT_FALSE(isPlausiblePose(Pose{{std::nan(""), 0, 0}, {}}, check));
  EXPECT_FALSE(isPlausiblePose(Pose{{}, {0.9, 0, 0, 0}}, check));  // not a rotation
  const Pose here{}, near{{0.005, 0, 0}, {}}, turned{{}, fromRotationVector({0, 0.05, 0})};
  EXPECT_TRUE(isPlausibleMotion(here, near, 0.001, 0.001, check));       // 5 m/s
  EXPECT_FALSE(isPlausibleMotion(here, near, 0.0001, 0.0001, check));    // 50 m/s
  EXPECT_TRUE(isPlausibleMotion(here, near, 0.0001, 0.001, check));      // floored at a period
  EXPECT_TRUE(isPlausibleMotion(here, turned, 0.001, 0.001, check));     // 50 rad/s
  EXPECT_FALSE(isPlausibleMotion(here, turned, 0.0001, 0.0001, check));  // 500 rad/s
  ReadingCheck bad;
  bad.max_speed = 0;
  EXPECT_EQ(bad.validate(), "reading.max_speed must be positive (m/s)");
}

TEST(HapticLoop, ThreadStartsTicksAndStopsWithZeroOutput) {
  ScriptedDevice device(pushAlongX(0.05), defaultDeviceLimits(), "thread");
  HapticLoop loop(device, HapticLoopSettings{});
  loop.start();
  // No speed is asserted: only that ticks happen at all, however loaded the machine is.
  for (int wait = 0; wait < 1000 && loop.stats().ticks < 20; ++wait) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  loop.stop();
  EXPECT_GE(loop.stats().ticks, 20u);
  EXPECT_EQ(norm(device.lastWritten().force), 0.0);
  EXPECT_FALSE(loop.running());
}

}  // namespace haptic_loop_test
}  // namespace torsion::device
