#include "torsion/device/passivity.h"

#include <cmath>

namespace torsion::device {

std::string PassivitySettings::validate() const {
  if (!(length_scale > 0 && std::isfinite(length_scale)))
    return "passivity.length_scale must be positive (m)";
  if (!(min_speed > 0 && std::isfinite(min_speed)))
    return "passivity.min_speed must be positive (m/s)";
  if (!(max_alpha > 0)) return "passivity.max_alpha must be positive (N s/m)";
  return {};
}

double power(const Wrench& w, const double v[6]) {
  return w.force.x * v[0] + w.force.y * v[1] + w.force.z * v[2] + w.torque.x * v[3] +
         w.torque.y * v[4] + w.torque.z * v[5];
}

Wrench PassivityController::damping(const Wrench& planned, const double v[6], double dt) {
  alpha_ = 0;
  if (!settings_.enabled || !(dt > 0)) return Wrench{};
  const double l2 = settings_.length_scale * settings_.length_scale;
  const double speed2 =
      v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + l2 * (v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
  const double predicted = energy_ + power(planned, v) * dt;
  if (!(predicted > 0) || !(speed2 > settings_.min_speed * settings_.min_speed)) return Wrench{};
  alpha_ = std::min(predicted / (speed2 * dt), settings_.max_alpha);
  if (!std::isfinite(alpha_)) {
    alpha_ = 0;
    return Wrench{};
  }
  dissipated_ += alpha_ * speed2 * dt;
  ++active_ticks_;
  return {{-alpha_ * v[0], -alpha_ * v[1], -alpha_ * v[2]},
          {-alpha_ * l2 * v[3], -alpha_ * l2 * v[4], -alpha_ * l2 * v[5]}};
}

void PassivityController::observe(const double v[6], double dt, bool holding) {
  if (!holding) {
    energy_ = 0;
    held_ = Wrench{};
    return;
  }
  const double delta = power(held_, v) * dt;
  if (std::isfinite(delta)) energy_ += delta;
  if (energy_ > max_energy_) max_energy_ = energy_;
}

}  // namespace torsion::device
