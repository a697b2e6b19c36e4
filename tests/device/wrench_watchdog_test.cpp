#include "torsion/device/wrench_watchdog.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "torsion/device/network_device.h"
#include "torsion/device/network_peer.h"
#include "torsion/device/pose_math.h"
#include "torsion/device/scripted_device.h"

// The device side's watchdog on a fake clock: what a device renders when the simulation's
// wrenches stop arriving (docs/haptics.md, "When the simulation dies").
namespace torsion::device {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace wrench_watchdog_test {

constexpr double kDt = 0.001;

DeviceLimits limits() {
  return defaultDeviceLimits();  // 30 N, 3 N m
}

const Wrench kHeld{{12, -16, 0}, {0, 1.5, -2}};  // 20 N, 2.5 N m

// Renders at 1 kHz from `from` to `to` (s), receiving kHeld at every tick before `stop` (s).
std::vector<Wrench> renderAt1kHz(WrenchWatchdog& watchdog, double from, double to, double stop) {
  std::vector<Wrench> out;
  for (int k = static_cast<int>(std::lround(from / kDt)); k * kDt <= to + 1e-12; ++k) {
    const double t = k * kDt;
    if (t < stop) watchdog.receive(kHeld, t);
    out.push_back(watchdog.render(t));
  }
  return out;
}

double forceStep(const WatchdogSettings& s) {
  return limits().max_force * kDt / s.fade_time;  // N per tick
}
double torqueStep(const WatchdogSettings& s) {
  return limits().max_torque * kDt / s.fade_time;  // N m per tick
}

TEST(WrenchWatchdog, PassesWrenchesThroughUnchangedWhileTheyArrive) {
  WrenchWatchdog watchdog(WatchdogSettings{}, limits());
  for (const Wrench& w : renderAt1kHz(watchdog, 0, 1, 2)) {
    EXPECT_EQ(w.force.x, kHeld.force.x);
    EXPECT_EQ(w.force.y, kHeld.force.y);
    EXPECT_EQ(w.torque.z, kHeld.torque.z);
  }
}

TEST(WrenchWatchdog, FadesToZeroAlongItsDirectionAsTheLoopDoesOnAStall) {
  // The last wrench at 0.999 s; after the timeout (0.1 s) the output shrinks at limit /
  // fade_time, so it is exactly zero at most fade_time (0.2 s) later.
  const WatchdogSettings settings;
  WrenchWatchdog watchdog(settings, limits());
  const std::vector<Wrench> out = renderAt1kHz(watchdog, 0, 2, 1.0);
  const double last = 0.999;
  for (size_t k = 1; k < out.size(); ++k) {
    const double t = static_cast<double>(k) * kDt;
    const Wrench& w = out[k];
    if (t < last + settings.timeout - 1e-9) {  // within the timeout: held
      EXPECT_EQ(norm(w.force), norm(kHeld.force)) << t;
      continue;
    }
    // Never grows, never steps faster than the fade, keeps its direction.
    EXPECT_LE(norm(out[k - 1].force) - norm(w.force), forceStep(settings) * (1 + 1e-9)) << t;
    EXPECT_LE(norm(out[k - 1].torque) - norm(w.torque), torqueStep(settings) * (1 + 1e-9)) << t;
    EXPECT_LE(norm(w.force), norm(out[k - 1].force)) << t;
    if (norm(w.force) > 0) {
      EXPECT_NEAR(w.force.x / norm(w.force), 0.6, 1e-12) << t;
      EXPECT_NEAR(w.force.y / norm(w.force), -0.8, 1e-12) << t;
    }
    if (t > last + settings.timeout + settings.fade_time + kDt) {
      EXPECT_EQ(norm(w.force), 0.0) << t;
      EXPECT_EQ(norm(w.torque), 0.0) << t;
    }
  }
  // 20 N at 150 N/s: gone 134 ticks after the timeout, before the fade time's 200.
  EXPECT_GT(
      norm(out[static_cast<size_t>(std::lround((last + settings.timeout + 0.1) / kDt))].force),
      0.0);
}

TEST(WrenchWatchdog, RenderedRarelyItStillFadesFromTheTimeoutAtTheFadeRate) {
  // A device host renders nothing while it waits: the first render 50 ms into the fade has
  // shrunk by 50 ms of fade, not by everything since the last wrench.
  const WatchdogSettings settings;
  WrenchWatchdog watchdog(settings, limits());
  watchdog.receive(kHeld, 1.0);
  EXPECT_EQ(norm(watchdog.render(1.0).force), norm(kHeld.force));
  const Wrench w = watchdog.render(1.0 + settings.timeout + 0.05);
  EXPECT_NEAR(norm(w.force), norm(kHeld.force) - limits().max_force * 0.05 / settings.fade_time,
              1e-9);
  EXPECT_NEAR(norm(w.torque), norm(kHeld.torque) - limits().max_torque * 0.05 / settings.fade_time,
              1e-9);
}

TEST(WrenchWatchdog, AWrenchAfterAFadeComesBackInAtTheFadeRateNotAsAStep) {
  const WatchdogSettings settings;
  WrenchWatchdog watchdog(settings, limits());
  renderAt1kHz(watchdog, 0, 1.5, 1.0);  // faded to zero by 1.3 s
  ASSERT_EQ(norm(watchdog.render(1.5).force), 0.0);
  const std::vector<Wrench> back = renderAt1kHz(watchdog, 1.501, 2.0, 3.0);
  Wrench previous;
  for (size_t k = 0; k < back.size(); ++k) {
    EXPECT_LE(norm(back[k].force - previous.force), forceStep(settings) * (1 + 1e-9)) << k;
    EXPECT_LE(norm(back[k].torque - previous.torque), torqueStep(settings) * (1 + 1e-9)) << k;
    previous = back[k];
  }
  // Within the fade time it renders what arrives again, exactly.
  EXPECT_EQ(back.back().force.x, kHeld.force.x);
  EXPECT_EQ(back.back().torque.z, kHeld.torque.z);
  // Also when nothing was rendered during the gap (a device host writes nothing while it holds
  // zero): the first render after the wrench returns is within one tick's step of zero.
  renderAt1kHz(watchdog, 2.001, 2.5, 2.0);  // faded again by 2.3 s; then no render until 5 s
  watchdog.receive(kHeld, 5.0);
  EXPECT_EQ(norm(watchdog.render(5.0).force), 0.0);
  EXPECT_LE(norm(watchdog.render(5.001).force), forceStep(settings) * (1 + 1e-9));
}

TEST(WrenchWatchdog, ALostSenderFadesAtOnceAndNothingLaterRevivesIt) {
  const WatchdogSettings settings;
  WrenchWatchdog watchdog(settings, limits());
  renderAt1kHz(watchdog, 0, 0.5, 1.0);
  watchdog.lost(0.5);
  EXPECT_TRUE(watchdog.fading(0.5));
  double t = 0.5;
  for (; !watchdog.faded() && t < 2; t += kDt) {
    watchdog.receive(kHeld, t);  // a stray packet of the gone sender
    watchdog.render(t);
  }
  EXPECT_TRUE(watchdog.faded());
  EXPECT_LE(t, 0.5 + settings.fade_time + kDt);
  EXPECT_EQ(norm(watchdog.render(t + 1).force), 0.0);
}

TEST(WrenchWatchdog, ATimeoutOfZeroFadesOnlyWhenTheSenderIsLost) {
  WatchdogSettings settings;
  settings.timeout = 0;
  WrenchWatchdog watchdog(settings, limits());
  renderAt1kHz(watchdog, 0, 0.1, 0.05);
  EXPECT_EQ(norm(watchdog.render(10).force), norm(kHeld.force));  // a 10 s lockstep pause
}

// The reference network peer renders through the watchdog: when the simulation stops sending
// (killed, stopped), its wrench fades to zero instead of being held.
TEST(NetworkPeer, TheRenderedWrenchFadesWhenTheSimulationStopsSending) {
  NetworkDeviceSettings device_settings;
  device_settings.local.port = 0;  // any free port
  device_settings.limits = defaultDeviceLimits();
  auto device = NetworkDevice::open(device_settings);
  ASSERT_TRUE(device) << device.error;
  auto peer = NetworkPeer::open((*device.value)->local(), Trajectory({{0, Pose{}}}, {}));
  ASSERT_TRUE(peer) << peer.error;
  NetworkDevice& sim = **device.value;
  NetworkPeer& p = **peer.value;
  double t = 0;
  for (; t < 0.5; t += kDt) {  // the simulation answers every pose (loopback: no waiting)
    p.tick(t);
    sim.read(t);
    sim.write(kHeld);
  }
  p.tick(t);  // takes the last wrench
  EXPECT_EQ(p.renderedWrench().force.x, kHeld.force.x);
  const WatchdogSettings settings;
  const double last = t;
  for (t += kDt; t <= last + settings.timeout + settings.fade_time + 2 * kDt; t += kDt)
    p.tick(t);  // the simulation is gone: nothing answers
  EXPECT_EQ(norm(p.renderedWrench().force), 0.0);
  EXPECT_EQ(norm(p.renderedWrench().torque), 0.0);
  EXPECT_EQ(p.newestWrench().force.x, kHeld.force.x);  // what last arrived, for the record
}

}  // namespace wrench_watchdog_test
}  // namespace torsion::device
