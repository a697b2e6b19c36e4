#include "torsion/device/plugin_device.h"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "stand_in_simulation.h"
#include "torsion/device/haptic_loop.h"
#include "torsion/device/pose_math.h"

// Device plug-ins loaded through the C ABI: the example simulated device in closed loop on a
// fake 1 kHz clock, and plug-ins that misbehave (NaN, non-unit quaternion, failing or blocking
// reads, a wrong ABI version), each both isolated in the device host and in process; plug-ins
// that crash, isolated only. Paths come from CMake (TORSION_*_PLUGIN, TORSION_DEVICE_HOST).
namespace torsion::device {
namespace {

constexpr double kDt = 0.001;

// A stand-in simulation at 100 Hz: a torsion spring about z (N m/rad) with its exact K_h.
struct TorsionSpring {
  double stiffness = 3;
  std::uint64_t step = 0;
  void answer(HapticLoop& loop) {
    HandCommand c;
    loop.commands().read(c);
    SimulationWrench w = answerTo(c, ++step);
    w.wrench.torque.z = -stiffness * toRotationVector(c.pose.orientation).z;
    w.stiffness[35] = -stiffness;
    loop.wrenches().write(w);
  }
};

// A simulation that pushes with a constant 5 N along x once grabbed.
struct ConstantPush {
  std::uint64_t step = 0;
  void answer(HapticLoop& loop) {
    HandCommand c;
    loop.commands().read(c);
    SimulationWrench w = answerTo(c, ++step);
    w.wrench.force.x = 5;
    loop.wrenches().write(w);
  }
};

// Where the plug-in runs: the parameter of the tests that hold either way.
class PluginDeviceAnywhere : public ::testing::TestWithParam<bool> {
 protected:
  PluginDeviceSettings settingsFor(const char* library) const {
    PluginDeviceSettings settings;
    settings.library = library;
    settings.isolated = GetParam();
    settings.host_program = TORSION_DEVICE_HOST;
    return settings;
  }
};

INSTANTIATE_TEST_SUITE_P(Both, PluginDeviceAnywhere, ::testing::Bool(),
                         [](const ::testing::TestParamInfo<bool>& where) {
                           return where.param ? "Isolated" : "InProcess";
                         });

PluginDeviceSettings isolatedSettings(const char* library) {
  PluginDeviceSettings settings;
  settings.library = library;
  settings.host_program = TORSION_DEVICE_HOST;
  return settings;
}

std::unique_ptr<PluginDevice> openOrFail(const PluginDeviceSettings& settings) {
  auto opened = PluginDevice::open(settings);
  EXPECT_TRUE(opened) << opened.error;
  return opened ? std::move(*opened.value) : nullptr;
}

TEST_P(PluginDeviceAnywhere,
       TheSimulatedDeviceTwistsAgainstASpringAndSettlesWhereTheWristBalancesIt) {
  PluginDeviceSettings settings = settingsFor(TORSION_SIMULATED_DEVICE_PLUGIN);
  // The operator turns the wrist 0.5 rad about z in 0.5 s and holds; the device's motors push
  // back with the spring's torque. Deadline generous: this checks the physics, not the clock.
  settings.config =
      "intent=twist,intent_rate=1,intent_start=0.1,intent_time=0.5,"
      "wrist_stiffness=3,max_torque=1";
  settings.read_deadline = 0.5;
  std::unique_ptr<PluginDevice> device = openOrFail(settings);
  ASSERT_TRUE(device);
  EXPECT_EQ(device->rateHz(), 1000);
  EXPECT_EQ(device->limits().max_torque, 1);
  EXPECT_NE(device->name().find("simulated"), std::string::npos) << device->name();

  HapticLoop loop(*device, HapticLoopSettings{});
  TorsionSpring spring;
  for (int k = 0; k <= 2500; ++k) {
    loop.tick(k * kDt);
    if (k % 10 == 0) spring.answer(loop);
  }
  EXPECT_EQ(device->stats().late, 0u);
  EXPECT_EQ(device->stats().reads, 2501u);
  EXPECT_EQ(loop.stats().nonfinite, 0u);
  EXPECT_TRUE(loop.forceEnabled());
  // Static balance: wrist K_w (0.5 - theta) = spring K theta, K_w = K = 3 N m/rad: 0.25 rad and
  // 0.75 N m (within the 1 N m limit).
  HandCommand c;
  loop.commands().read(c);
  const double theta = toRotationVector(c.pose.orientation).z;
  EXPECT_NEAR(theta, 0.25, 0.25 * 0.03);
  EXPECT_NEAR(loop.lastOutput().torque.z, -0.75, 0.75 * 0.03);
  // The spring stored energy and gave none back: the port stayed passive, the controller idle.
  EXPECT_LE(loop.stats().max_port_energy.load(), 1e-9);
  EXPECT_EQ(loop.stats().pc_active, 0u);
}

TEST_P(PluginDeviceAnywhere, AWrongAbiVersionIsRefusedWithBothVersionsNamed) {
  PluginDeviceSettings settings = settingsFor(TORSION_WRONG_ABI_PLUGIN);
  auto opened = PluginDevice::open(settings);
  ASSERT_FALSE(opened);
  EXPECT_NE(opened.error.find("ABI version 99"), std::string::npos) << opened.error;
  EXPECT_NE(opened.error.find("speaks version 1"), std::string::npos) << opened.error;
}

TEST_P(PluginDeviceAnywhere, AMissingLibraryAnAlienLibraryAndABadConfigAreClearErrors) {
  PluginDeviceSettings settings = settingsFor("/nonexistent/libnodevice.so");
  auto missing = PluginDevice::open(settings);
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error.find("cannot load"), std::string::npos) << missing.error;

  settings.library = "libm.so.6";  // a real library without the entry point
  auto alien = PluginDevice::open(settings);
  ASSERT_FALSE(alien);
  EXPECT_NE(alien.error.find("no entry point 'torsion_device_plugin'"), std::string::npos)
      << alien.error;

  settings.library = TORSION_SIMULATED_DEVICE_PLUGIN;
  settings.config = "device_mass=heavy";
  auto bad = PluginDevice::open(settings);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error.find("device_mass: 'heavy' is not a number"), std::string::npos) << bad.error;
  EXPECT_EQ(bad.error.rfind(settings.library + ": ", 0), 0u) << bad.error;
}

// Runs a faulty plug-in under a constant 5 N push until `until` s; the fault starts at 0.3 s.
struct FaultRun {
  double before = 0;      // N written just before the fault
  double at_end = -1;     // N written at `until`
  double zero_from = -1;  // s, loop time from which the output stayed exactly zero
  bool always_finite = true;
  bool alive_at_end = true;
};

FaultRun runFaulty(PluginDevice& device, double until) {
  HapticLoop loop(device, HapticLoopSettings{});
  ConstantPush sim;
  FaultRun run;
  for (int k = 0; k * kDt <= until + 1e-9; ++k) {
    loop.tick(k * kDt);
    sim.answer(loop);
    const Wrench& w = loop.lastOutput();
    run.always_finite = run.always_finite && isFinite(w);
    if (k == 299) run.before = norm(w.force);
    if (norm(w.force) != 0)
      run.zero_from = -1;
    else if (run.zero_from < 0)
      run.zero_from = k * kDt;
  }
  HandCommand c;
  loop.commands().read(c);
  run.alive_at_end = c.alive;
  run.at_end = norm(loop.lastOutput().force);
  return run;
}

TEST_P(PluginDeviceAnywhere, NanNonUnitQuaternionAndFailedReadsFadeTheForceAndAreCounted) {
  for (const char* fault : {"nan", "quat", "fail"}) {
    SCOPED_TRACE(fault);
    PluginDeviceSettings settings = settingsFor(TORSION_FAULTY_PLUGIN);
    settings.config = std::string("fault=") + fault + ",after=0.3";
    settings.read_deadline = 0.5;
    std::unique_ptr<PluginDevice> device = openOrFail(settings);
    ASSERT_TRUE(device);
    // Fault at 0.3 s, held 5 ms, then dead: zero within fade_time (0.2 s) after that.
    const FaultRun run = runFaulty(*device, 0.3 + 0.005 + 0.2 + 0.002);
    EXPECT_NEAR(run.before, 5, 1e-9);  // healthy: the push was rendered in full
    EXPECT_EQ(run.at_end, 0);
    EXPECT_TRUE(run.always_finite);
    EXPECT_FALSE(run.alive_at_end);
    const PluginStats& s = device->stats();
    EXPECT_GT(std::string(fault) == "fail" ? s.failed.load() : s.rejected.load(), 190u);
    EXPECT_NEAR(static_cast<double>(s.held.load()), 5, 1);  // hold_time / tick, to rounding
    EXPECT_EQ(s.late, 0u);
  }
}

TEST_P(PluginDeviceAnywhere, APluginThatBlocksMissesItsDeadlinesTheLoopGoesOnAndTheForceFades) {
  PluginDeviceSettings settings = settingsFor(TORSION_FAULTY_PLUGIN);
  settings.config = "fault=block,after=0.3,block_ms=30";
  settings.read_deadline = 0.002;
  std::unique_ptr<PluginDevice> device = openOrFail(settings);
  ASSERT_TRUE(device);
  HapticLoop loop(*device, HapticLoopSettings{});
  ConstantPush sim;
  double before = 0, after_fault = 0;
  for (int k = 0; k * kDt <= 0.3 + 0.005 + 0.2 + 0.002; ++k) {
    const auto start = std::chrono::steady_clock::now();
    loop.tick(k * kDt);
    if (k >= 300)
      after_fault +=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    sim.answer(loop);
    if (k == 299 && device->stats().late == 0) before = norm(loop.lastOutput().force);
  }
  // Before the fault the push was rendered in full (unless this busy machine made a healthy read
  // late, which the check skips). After it, 208 ticks waited at most their 2 ms deadline each:
  // had they waited for the plug-in's 30 ms reads they would have taken over 6 s (1.5 s allowed
  // for a busy machine's scheduler).
  if (before > 0) {
    EXPECT_NEAR(before, 5, 1e-9);
  }
  EXPECT_LT(after_fault, 1.5);
  EXPECT_GT(device->stats().late, 150u);
  EXPECT_EQ(norm(loop.lastOutput().force), 0);
}

// A read() that never returns, with the lockstep deadline (0.1 s): each tick waiting for it
// would make the run 100 times slower than the simulation. Once it has been inside the plug-in
// for hung_timeout the device stops waiting for it and is dead.
TEST_P(PluginDeviceAnywhere, AHungReadCostsTheLoopItsDeadlineOnlyUntilTheHungTimeout) {
  PluginDeviceSettings settings = settingsFor(TORSION_FAULTY_PLUGIN);
  settings.config = "fault=block,after=0.05,block_ms=5000";
  settings.read_deadline = 0.1;
  settings.hung_timeout = 0.3;
  std::unique_ptr<PluginDevice> device = openOrFail(settings);
  ASSERT_TRUE(device);
  for (int k = 0; k < 50; ++k)
    device->read(k * kDt);
  const auto start = std::chrono::steady_clock::now();
  DeviceSample last;
  for (int k = 50; k < 150; ++k)
    last = device->read(k * kDt);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Waiting 0.1 s per tick until the read has been hung for 0.3 s, then not at all: about 0.4 s
  // (2 s allowed for a busy machine) where 100 full deadlines would take 10 s.
  EXPECT_LT(took, 2.0);
  EXPECT_FALSE(last.alive);
  EXPECT_GE(device->stats().late.load(), 100u);
}

// An open() that never returns fails after start_timeout, naming the plug-in, instead of hanging
// Torsion before its first step.
TEST_P(PluginDeviceAnywhere, AnOpenThatNeverReturnsFailsAfterTheStartTimeout) {
  PluginDeviceSettings settings = settingsFor(TORSION_FAULTY_PLUGIN);
  settings.config = "open_block_ms=5000";
  settings.start_timeout = 0.3;
  const auto start = std::chrono::steady_clock::now();
  auto opened = PluginDevice::open(settings);
  const double took =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_FALSE(opened);
  EXPECT_EQ(opened.error.rfind(std::string(TORSION_FAULTY_PLUGIN) + ": ", 0), 0u) << opened.error;
  EXPECT_NE(opened.error.find("within 0.3"), std::string::npos) << opened.error;
  EXPECT_LT(took, 0.3 + 2.0);  // the timeout, and what a busy machine adds (a killed host: 1 s)
}

// A plug-in that crashes, isolated: the fault starts at 0.3 s; the last good reading (0.299 s) is
// held 5 ms, then the device is dead and the safety filter fades 5 N to zero in its fade_time
// (0.2 s). The host's death is reported with its signal and the host is reaped.
void expectCrashSurvived(const std::string& config, const std::string& signal_text) {
  PluginDeviceSettings settings = isolatedSettings(TORSION_FAULTY_PLUGIN);
  settings.config = config;
  settings.read_deadline = 0.5;  // fake clock: this checks the rules, not the machine's speed
  std::unique_ptr<PluginDevice> device = openOrFail(settings);
  ASSERT_TRUE(device);
  const int pid = device->hostProcessId();
  ASSERT_GT(pid, 0);
  const double hold = settings.hold_time, fade = HapticLoopSettings{}.safety.fade_time;
  const FaultRun run = runFaulty(*device, 0.3 + hold + fade + 0.05);
  EXPECT_NEAR(run.before, 5, 1e-9);
  EXPECT_TRUE(run.always_finite);
  EXPECT_FALSE(run.alive_at_end);
  EXPECT_EQ(run.at_end, 0);
  // Held, then faded (not cut), and exactly zero within fade_time after the hold, to a tick.
  EXPECT_GT(run.zero_from, 0.3 + hold);
  EXPECT_LE(run.zero_from, 0.3 + hold + fade + 2 * kDt);
  EXPECT_NEAR(static_cast<double>(device->stats().held.load()), 5, 1);
  EXPECT_NE(device->hostExit().find(signal_text), std::string::npos) << device->hostExit();
  // Reaped as soon as its death was seen: no zombie left, neither now nor after close.
  int status = 0;
  EXPECT_EQ(waitpid(pid, &status, WNOHANG), -1);
  EXPECT_EQ(errno, ECHILD);
  device.reset();
  EXPECT_EQ(waitpid(pid, &status, WNOHANG), -1);
}

TEST(PluginDeviceHost, APluginThatSegfaultsEndsOnlyItsHostTheForceFadesAndTheSignalIsReported) {
  expectCrashSurvived("fault=segv,after=0.3", "killed by signal 11 (SIGSEGV)");
}

TEST(PluginDeviceHost, APluginThatAbortsAfterNReadsEndsOnlyItsHostAndTheSignalIsReported) {
  // Reads at 0, 1, ..., 299 ms answer; the 301st (0.3 s) aborts.
  expectCrashSurvived("fault=abort,reads=301", "killed by signal 6 (SIGABRT)");
}

TEST(PluginDeviceHost, AHealthyHostIsClosedAndReapedWithTheDeviceAndReportsNoExit) {
  PluginDeviceSettings settings = isolatedSettings(TORSION_FAULTY_PLUGIN);
  settings.read_deadline = 0.5;
  std::unique_ptr<PluginDevice> device = openOrFail(settings);
  ASSERT_TRUE(device);
  const int pid = device->hostProcessId();
  EXPECT_NE(pid, getpid());
  const FaultRun run = runFaulty(*device, 0.05);
  EXPECT_TRUE(run.alive_at_end);
  EXPECT_EQ(device->hostExit(), "");
  device.reset();
  int status = 0;
  EXPECT_EQ(waitpid(pid, &status, WNOHANG), -1);  // reaped: not our child any more
  EXPECT_EQ(errno, ECHILD);
}

// The force norms (N) of the wrenches a plug-in given log=PATH was written, in order.
std::vector<double> loggedForces(const std::string& path) {
  std::vector<double> forces;
  std::ifstream in(path);
  double w[6];
  while (in >> w[0] >> w[1] >> w[2] >> w[3] >> w[4] >> w[5])
    forces.push_back(std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]));
  return forces;
}

// Torsion stopped (SIGSTOP), hung, or gone without a word (SIGKILL): its wrenches stop coming,
// and the host fades the one the plug-in renders to zero by itself, as the haptic loop fades on
// a stall (wrench_watchdog.h), instead of leaving the device pushing. The faulty plug-in logs
// every wrench it is given.
TEST(PluginDeviceHost, WhenTorsionStopsSendingTheHostFadesTheWrenchToZeroByItself) {
  const std::string log = ::testing::TempDir() + "host_watchdog_writes.txt";
  std::remove(log.c_str());
  PluginDeviceSettings settings = isolatedSettings(TORSION_FAULTY_PLUGIN);
  settings.config = "log=" + log;
  settings.read_deadline = 0.5;  // a loaded machine must not make these reads late
  std::unique_ptr<PluginDevice> device = openOrFail(settings);
  ASSERT_TRUE(device);
  const Wrench held{{10, 0, 0}, {0, 0, 1}};  // within the plug-in's 20 N, 2 N m
  for (int k = 0; k < 20; ++k) {             // each read carries the wrench written before it
    device->write(held);
    device->read(k * kDt);
  }
  // Nothing more comes: wait well past the timeout (0.1 s) and the fade (0.2 s from the limit).
  std::this_thread::sleep_for(std::chrono::milliseconds(600));
  const std::vector<double> forces = loggedForces(log);
  ASSERT_GE(forces.size(), 20u);
  EXPECT_EQ(forces.back(), 0.0);
  // A fade, not a cut: down from 10 N through values in between, never rising.
  size_t last_held = 0;
  for (size_t k = 0; k < forces.size(); ++k)
    if (forces[k] == 10) last_held = k;
  size_t between = 0;
  for (size_t k = last_held + 1; k < forces.size(); ++k) {
    EXPECT_LE(forces[k], forces[k - 1]) << k;
    if (forces[k] > 0 && forces[k] < 10) ++between;
  }
  EXPECT_GT(between, 0u);
  device.reset();
  std::remove(log.c_str());
}

TEST(PluginDeviceHost, AMissingHostProgramIsAClearError) {
  PluginDeviceSettings settings = isolatedSettings(TORSION_FAULTY_PLUGIN);
  settings.host_program = "/nonexistent/torsion_device_host";
  auto opened = PluginDevice::open(settings);
  ASSERT_FALSE(opened);
  EXPECT_NE(opened.error.find("cannot start the device host '/nonexistent/torsion_device_host'"),
            std::string::npos)
      << opened.error;
  settings.host_program.clear();
  auto unset = PluginDevice::open(settings);
  ASSERT_FALSE(unset);
  EXPECT_NE(unset.error.find("host_program"), std::string::npos) << unset.error;
}

}  // namespace
}  // namespace torsion::device
