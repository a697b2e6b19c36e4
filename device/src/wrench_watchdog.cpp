#include "torsion/device/wrench_watchdog.h"

#include <algorithm>
#include <cmath>

#include "torsion/device/pose_math.h"
#include "torsion/device/wrench_safety.h"

namespace torsion::device {

WrenchWatchdog::WrenchWatchdog(const WatchdogSettings& settings, const DeviceLimits& limits)
    : settings_(settings), limits_(limits) {}

void WrenchWatchdog::receive(const Wrench& wrench, double time) {
  if (lost_) return;  // a sender that is gone sends nothing more; a stray packet changes nothing
  // The first wrench after a fade: the ramp back starts now, however long ago the last render
  // was (a device host renders nothing while it holds zero).
  if (fading(time)) resumed_at_ = time;
  received_ = saturate(wrench, limits_);
  received_at_ = time;
  have_received_ = true;
}

void WrenchWatchdog::lost(double time) {
  if (lost_) return;
  lost_ = true;
  lost_at_ = time;
}

bool WrenchWatchdog::fading(double time) const {
  if (lost_ && time >= lost_at_) return true;
  return have_received_ && settings_.timeout > 0 && time - received_at_ > settings_.timeout;
}

Vec3 WrenchWatchdog::moveToward(const Vec3& from, const Vec3& to, double step) const {
  const Vec3 d = to - from;
  const double n = norm(d);
  // A hair of slack, as in the safety filter, so that rounding cannot leave 1e-13 N, not 0.
  if (n <= step * (1 + 1e-9)) return to;
  return from + (step / n) * d;
}

double WrenchWatchdog::fadeStart() const {
  if (lost_) return lost_at_;
  return received_at_ + settings_.timeout;
}

Wrench WrenchWatchdog::render(double time) {
  // The fade and the ramp back run from when they started, however long ago the last render was
  // (a device host renders nothing while it waits): never more than their rate allows.
  const bool fade = fading(time);
  double since = std::max(rendered_at_, resumed_at_);
  if (fade) since = std::max(since, fadeStart());
  const double dt = have_rendered_ ? std::clamp(time - since, 0.0, settings_.fade_time) : 0;
  have_rendered_ = true;
  rendered_at_ = time;
  const double force_step = limits_.max_force * dt / settings_.fade_time;
  const double torque_step = limits_.max_torque * dt / settings_.fade_time;
  if (fade) {
    // Shrink along the output's own direction, as the loop's safety filter does on a stall.
    output_ = {moveToward(output_.force, Vec3{}, force_step),
               moveToward(output_.torque, Vec3{}, torque_step)};
    recovering_ = true;
  } else if (recovering_) {
    output_ = {moveToward(output_.force, received_.force, force_step),
               moveToward(output_.torque, received_.torque, torque_step)};
    const Wrench gap = received_ + (-1.0) * output_;
    recovering_ = norm(gap.force) > 0 || norm(gap.torque) > 0;
  } else {
    output_ = received_;
  }
  faded_ = lost_ && norm(output_.force) == 0 && norm(output_.torque) == 0;
  return output_;
}

}  // namespace torsion::device
