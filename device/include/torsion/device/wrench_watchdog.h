#pragma once
// The device side's own guard against a simulation that died: the wrench a device renders
// fades to zero when wrenches stop arriving, whatever stopped them (the simulation killed,
// stopped, hung, or its host gone). The haptic loop fades its output on a stall, but only while
// it runs; a loop that is killed or stopped writes nothing more, and a device that holds its
// last wrench would go on pushing the hand. The reference network peer and the plug-in host keep
// one of these between what they receive and what they render.
//
// The fade is the haptic loop's on a stall (wrench_safety.h): after `timeout` without a new
// wrench the output shrinks along its direction at limit / fade_time, so it is exactly zero at
// most fade_time later. A wrench that arrives after a fade comes back in at the same rate, not as
// a step. While wrenches keep arriving the watchdog passes them through unchanged (saturated to
// the limits). Time is an argument (any monotonic clock, in seconds), so it is tested without
// sleeping.

#include "torsion/device/device_types.h"

namespace torsion::device {

struct WatchdogSettings {
  /// s without a new wrench before the fade starts: the haptic loop's stale_after; 0: never
  /// (only lost() starts the fade).
  double timeout = 0.1;
  double fade_time = 0.2;  ///< s: a faded output reaches zero within this, from the limit
};

class WrenchWatchdog {
 public:
  WrenchWatchdog(const WatchdogSettings& settings, const DeviceLimits& limits);

  /// A wrench from the simulation arrived at `time`.
  void receive(const Wrench& wrench, double time);
  /// The sender is gone for good as of `time` (its process ended): fade from now on, without
  /// waiting for the timeout.
  void lost(double time);
  /// The wrench to render at `time` (non-decreasing from call to call).
  Wrench render(double time);
  /// True when the output is fading at `time` (timed out, or lost()).
  bool fading(double time) const;
  /// True when the output is zero and nothing newer is to come in: a device may stop writing.
  bool faded() const { return faded_; }

 private:
  Vec3 moveToward(const Vec3& from, const Vec3& to, double step) const;
  /// s: when the current fade started (lost(), or the timeout after the last wrench).
  double fadeStart() const;

  WatchdogSettings settings_;
  DeviceLimits limits_;
  Wrench received_;
  double received_at_ = 0;
  bool have_received_ = false;
  bool lost_ = false;
  double lost_at_ = 0;
  Wrench output_;
  double rendered_at_ = 0;
  double resumed_at_ = 0;  // the first wrench after a fade came then
  bool have_rendered_ = false;
  bool recovering_ = false;  // a wrench came after a fade: ramping back in to it
  bool faded_ = false;
};

}  // namespace torsion::device
