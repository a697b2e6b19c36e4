#include "torsion/device/spacemouse_integrator.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "torsion/device/pose_math.h"

namespace torsion::device {

std::string SpaceMouseSettings::validate() const {
  if (!(full_scale > 0)) return "full_scale must be > 0 counts";
  if (!(max_linear_speed >= 0) || !std::isfinite(max_linear_speed))
    return "max_linear_speed must be >= 0 m/s";
  if (!(max_angular_speed >= 0) || !std::isfinite(max_angular_speed))
    return "max_angular_speed must be >= 0 rad/s";
  if (dead_zone < 0 || dead_zone >= full_scale) return "dead_zone must be in [0, full_scale)";
  if (!(max_step > 0)) return "max_step must be > 0 s";
  if (!(workspace_min.x <= 0 && workspace_min.y <= 0 && workspace_min.z <= 0 &&
        workspace_max.x >= 0 && workspace_max.y >= 0 && workspace_max.z >= 0))
    return "the workspace box must contain the origin";
  return {};
}

double SpaceMouseIntegrator::speedFraction(int counts) const {
  // Dead zone, then linear up to full scale: the speed starts from zero at the dead zone's edge
  // instead of jumping there.
  const double magnitude = std::abs(counts) - settings_.dead_zone;
  if (magnitude <= 0) return 0;
  const double fraction = std::min(1.0, magnitude / (settings_.full_scale - settings_.dead_zone));
  return counts < 0 ? -fraction : fraction;
}

void SpaceMouseIntegrator::twistOf(const SpaceMouseReading& r, Vec3& linear, Vec3& angular) const {
  const double v = settings_.max_linear_speed, w = settings_.max_angular_speed;
  linear = {v * speedFraction(r.translation[0]), v * speedFraction(r.translation[1]),
            v * speedFraction(r.translation[2])};
  angular = {w * speedFraction(r.rotation[0]), w * speedFraction(r.rotation[1]),
             w * speedFraction(r.rotation[2])};
}

const Pose& SpaceMouseIntegrator::advance(double time) {
  if (!started_) {
    started_ = true;
    time_ = time;
    return pose_;
  }
  const double dt = std::clamp(time - time_, 0.0, settings_.max_step);
  time_ = time;
  Vec3 linear, angular;
  twistOf(reading_, linear, angular);
  Vec3 p = pose_.position + dt * linear;
  p.x = std::clamp(p.x, settings_.workspace_min.x, settings_.workspace_max.x);
  p.y = std::clamp(p.y, settings_.workspace_min.y, settings_.workspace_max.y);
  p.z = std::clamp(p.z, settings_.workspace_min.z, settings_.workspace_max.z);
  pose_.position = p;
  // The twist is about fixed device axes: left-multiply by the small rotation.
  pose_.orientation = normalized(fromRotationVector(dt * angular) * pose_.orientation);
  return pose_;
}

}  // namespace torsion::device
