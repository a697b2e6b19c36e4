#pragma once
// Pure functions that keep a wrench safe for the hand. Every wrench goes through them before a
// device sees it.

#include <string>

#include "torsion/device/device_types.h"

namespace torsion::device {

/// True when all six components are finite.
bool isFinite(const Wrench& wrench);

/// Scales force and torque (each as a vector, so direction is kept) down to the device's limits.
/// A wrench with any non-finite component becomes zero: NaN never reaches a device.
Wrench saturate(const Wrench& wrench, const DeviceLimits& limits);

/// The safety rules of docs/design.md section 4, with their time constants.
struct SafetySettings {
  double max_force_rate = 300;  ///< N/s: output force never changes faster
  double max_torque_rate = 30;  ///< N m/s
  double stale_after = 0.1;     ///< s without a new simulation wrench: the simulation stalled
  double fade_time = 0.2;       ///< s: an unhealthy output reaches zero within this, from the limit

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

/// Why the filter is fading, or not.
struct SafetyInputs {
  bool device_alive = false;
  bool simulation_fresh = false;  ///< a simulation wrench arrived within stale_after
  bool grabbed = false;           ///< a patch is held and force output is enabled (button 1)
};

/// The last stage before a device: saturation, rate-of-change limit and fade, one tick at a time.
///   - healthy and grabbed: the output follows saturate(desired), at most max_*_rate per second,
///     faded back in over fade_time after any unhealthy spell;
///   - healthy, nothing grabbed: the output goes to zero at the rate limit;
///   - device dead or simulation stale: the output shrinks (direction kept) at limit / fade_time,
///     so it is exactly zero at most fade_time later, whatever it was.
/// The output is always finite and within the limits; it never jumps.
class SafetyFilter {
 public:
  SafetyFilter(const SafetySettings& settings, const DeviceLimits& limits);
  /// `dt`: s since the previous tick (clamped to [0, fade_time]).
  Wrench apply(const Wrench& desired, const SafetyInputs& inputs, double dt);
  const Wrench& output() const { return output_; }
  /// A later stage's (the passivity controller's) change of this tick's output: `proposed`,
  /// moved to within the rate limit of the last tick's output and saturated, becomes the output,
  /// which is returned for the device. The rate limit stays the last stage before the device
  /// whatever the later stage asks for, and the next tick starts from what the device holds.
  /// `dt` as for apply() (the same tick's).
  const Wrench& follow(const Wrench& proposed, double dt);
  double gain() const { return gain_; }

 private:
  SafetySettings settings_;
  DeviceLimits limits_;
  Wrench output_;
  Wrench previous_;  // the last tick's output: where this tick's rate limit is measured from
  double gain_ = 0;  // fade-in gain in [0, 1]
};

}  // namespace torsion::device
