#include "torsion/device/reading_check.h"

#include <algorithm>
#include <cmath>

#include "torsion/device/pose_math.h"

namespace torsion::device {

namespace {

// A unit quaternion's norm, to the tolerance the plug-in loader uses: a device's own rounding
// passes, a field that is not a rotation does not.
constexpr double kUnitTolerance = 1e-3;

bool isPositiveFinite(double v) {
  return v > 0 && std::isfinite(v);
}

}  // namespace

std::string ReadingCheck::validate() const {
  if (!isPositiveFinite(max_reach)) return "reading.max_reach must be positive (m)";
  if (!isPositiveFinite(max_speed)) return "reading.max_speed must be positive (m/s)";
  if (!isPositiveFinite(max_angular_speed))
    return "reading.max_angular_speed must be positive (rad/s)";
  if (!(hold_time >= 0 && hold_time <= 1)) return "reading.hold_time must be in [0, 1] s";
  return {};
}

bool isPlausiblePose(const Pose& pose, const ReadingCheck& check) {
  const Quat& q = pose.orientation;
  const double q_norm = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  return isFinite(pose.position) && std::abs(q_norm - 1) <= kUnitTolerance &&
         norm(pose.position) <= check.max_reach;
}

bool isPlausibleMotion(const Pose& from, const Pose& to, double elapsed, double min_elapsed,
                       const ReadingCheck& check) {
  const double t = std::max(elapsed, min_elapsed);
  double delta[6];
  poseDifference(from, to, delta);
  const double moved = std::sqrt(delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]);
  const double turned = std::sqrt(delta[3] * delta[3] + delta[4] * delta[4] + delta[5] * delta[5]);
  return moved <= check.max_speed * t && turned <= check.max_angular_speed * t;
}

}  // namespace torsion::device
