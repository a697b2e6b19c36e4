#include "torsion/device/wrench_safety.h"

#include <algorithm>
#include <cmath>

#include "torsion/device/pose_math.h"

namespace torsion::device {

bool isFinite(const Wrench& wrench) {
  return isFinite(wrench.force) && isFinite(wrench.torque);
}

Wrench saturate(const Wrench& wrench, const DeviceLimits& limits) {
  if (!isFinite(wrench)) return Wrench{};
  return {clampNorm(wrench.force, limits.max_force), clampNorm(wrench.torque, limits.max_torque)};
}

}  // namespace torsion::device

namespace torsion::device {

namespace {

// Shrinks `v` towards zero by `step` along its own direction.
Vec3 shrink(const Vec3& v, double step) {
  return approach(v, Vec3{}, step);
}

}  // namespace

std::string SafetySettings::validate() const {
  if (!(max_force_rate > 0)) return "max_force_rate must be positive (N/s)";
  if (!(max_torque_rate > 0)) return "max_torque_rate must be positive (N m/s)";
  if (!(stale_after > 0)) return "stale_after must be positive (s)";
  if (!(fade_time > 0)) return "fade_time must be positive (s)";
  return {};
}

SafetyFilter::SafetyFilter(const SafetySettings& settings, const DeviceLimits& limits)
    : settings_(settings), limits_(limits) {}

namespace {

double clampedStep(double dt, double fade_time) {
  return std::isfinite(dt) ? std::clamp(dt, 0.0, fade_time) : 0.0;
}

}  // namespace

Wrench SafetyFilter::apply(const Wrench& desired, const SafetyInputs& inputs, double dt) {
  dt = clampedStep(dt, settings_.fade_time);
  previous_ = output_;
  if (!inputs.device_alive || !inputs.simulation_fresh) {
    gain_ = 0;
    output_.force = shrink(output_.force, limits_.max_force * dt / settings_.fade_time);
    output_.torque = shrink(output_.torque, limits_.max_torque * dt / settings_.fade_time);
    return output_;
  }
  Wrench target;  // zero when nothing is grabbed
  if (inputs.grabbed) {
    gain_ = std::min(1.0, gain_ + dt / settings_.fade_time);
    const Wrench safe = saturate(desired, limits_);
    target = {{gain_ * safe.force.x, gain_ * safe.force.y, gain_ * safe.force.z},
              {gain_ * safe.torque.x, gain_ * safe.torque.y, gain_ * safe.torque.z}};
  } else {
    gain_ = 0;
  }
  output_.force = approach(output_.force, target.force, settings_.max_force_rate * dt);
  output_.torque = approach(output_.torque, target.torque, settings_.max_torque_rate * dt);
  output_ = saturate(output_, limits_);
  return output_;
}

const Wrench& SafetyFilter::follow(const Wrench& proposed, double dt) {
  dt = clampedStep(dt, settings_.fade_time);
  const Wrench safe = saturate(proposed, limits_);
  output_.force = approach(previous_.force, safe.force, settings_.max_force_rate * dt);
  output_.torque = approach(previous_.torque, safe.torque, settings_.max_torque_rate * dt);
  output_ = saturate(output_, limits_);
  return output_;
}

}  // namespace torsion::device
