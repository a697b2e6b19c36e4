#include "torsion/device/passivity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "torsion/device/pose_math.h"
#include "torsion/device/wrench_safety.h"

namespace torsion::device {

std::string PassivitySettings::validate() const {
  if (!(length_scale > 0 && std::isfinite(length_scale)))
    return "passivity.length_scale must be positive (m)";
  if (!(min_speed > 0 && std::isfinite(min_speed)))
    return "passivity.min_speed must be positive (m/s)";
  if (!(max_alpha > 0)) return "passivity.max_alpha must be positive (N s/m)";
  if (!(energy_tolerance >= 0 && std::isfinite(energy_tolerance)))
    return "passivity.energy_tolerance must be non-negative (J)";
  if (!(speed_hold_time > 0 && std::isfinite(speed_hold_time)))
    return "passivity.speed_hold_time must be positive (s)";
  if (!(speed_margin >= 1 && std::isfinite(speed_margin)))
    return "passivity.speed_margin must be at least 1";
  if (!(misprediction_margin >= 0 && std::isfinite(misprediction_margin)))
    return "passivity.misprediction_margin must be non-negative";
  return {};
}

double power(const Wrench& w, const double v[6]) {
  return w.force.x * v[0] + w.force.y * v[1] + w.force.z * v[2] + w.torque.x * v[3] +
         w.torque.y * v[4] + w.torque.z * v[5];
}

namespace {

double norm3(const Vec3& v) {
  return std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
}

Vec3 lerp(const Vec3& a, const Vec3& b, double u) {
  return {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)};
}

Vec3 clampNorm(const Vec3& v, double limit) {
  const double n = norm3(v);
  if (!(n > limit)) return v;
  const double s = limit / n;
  return {s * v.x, s * v.y, s * v.z};
}

// `from` moved toward `to` by at most `step`.
Vec3 approach(const Vec3& from, const Vec3& to, double step) {
  const Vec3 d{to.x - from.x, to.y - from.y, to.z - from.z};
  const Vec3 limited = clampNorm(d, step);
  return {from.x + limited.x, from.y + limited.y, from.z + limited.z};
}

// One part (force or torque) of the reserve need: the work of `w` over the coming tick at
// velocity `v`, plus what ramping |w| to zero at `rate` (per s) could give out at `speed`.
double partNeed(const Vec3& w, const Vec3& v, double dt, double speed, double rate) {
  const double work = (w.x * v.x + w.y * v.y + w.z * v.z) * dt;
  return work + (rate > 0 ? (w.x * w.x + w.y * w.y + w.z * w.z) * speed / (2 * rate) : 0.0);
}

// The wrench part within `step` of `from` with the least partNeed: toward its minimiser
// -v dt rate / speed (straight against v when the speed bound is zero).
Vec3 brakePart(const Vec3& from, const Vec3& v, double dt, double speed, double rate, double step) {
  if (speed > 0 && rate > 0) {
    const double s = dt * rate / speed;
    return approach(from, {-s * v.x, -s * v.y, -s * v.z}, step);
  }
  const double n = norm3(v);
  if (!(n > 0)) return from;
  return {from.x - step * v.x / n, from.y - step * v.y / n, from.z - step * v.z / n};
}

}  // namespace

double PassivityController::reserveNeed(const Wrench& w, const double v[6], double dt,
                                        double force_rate, double torque_rate) const {
  const double m = settings_.speed_margin;
  return energy_ - settings_.energy_tolerance +
         partNeed(w.force, {v[0], v[1], v[2]}, dt, m * speed_bound_[0], force_rate) +
         partNeed(w.torque, {v[3], v[4], v[5]}, dt, m * speed_bound_[1], torque_rate);
}

Wrench PassivityController::limit(const Wrench& previous, const Wrench& planned, const double v[6],
                                  double dt, double force_step, double torque_step,
                                  const DeviceLimits& limits) {
  alpha_ = 0;
  if (!settings_.enabled || !(dt > 0)) return planned;
  const double force_rate = force_step / dt, torque_rate = torque_step / dt;
  if (!(reserveNeed(planned, v, dt, force_rate, torque_rate) > 0)) return planned;
  // The brake: the wrench within the rate limit of the last one written with the least need.
  // Saturation projects onto the limit balls, which keeps it within the rate limit of
  // `previous` (itself within the limits).
  const Wrench brake{clampNorm(brakePart(previous.force, {v[0], v[1], v[2]}, dt, speed_bound_[0],
                                         force_rate, force_step),
                               limits.max_force),
                     clampNorm(brakePart(previous.torque, {v[3], v[4], v[5]}, dt, speed_bound_[1],
                                         torque_rate, torque_step),
                               limits.max_torque)};
  // The least change from the plan toward the brake that covers the need (the need is convex
  // along the segment; the brake's end when even the brake does not).
  auto at = [&](double u) {
    return Wrench{lerp(planned.force, brake.force, u), lerp(planned.torque, brake.torque, u)};
  };
  double u = 1;
  if (!(reserveNeed(brake, v, dt, force_rate, torque_rate) > 0)) {
    double lo = 0, hi = 1;
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (lo + hi);
      (reserveNeed(at(mid), v, dt, force_rate, torque_rate) > 0 ? lo : hi) = mid;
    }
    u = hi;
  }
  const Wrench out = at(u);
  const double l2 = settings_.length_scale * settings_.length_scale;
  const double speed2 =
      v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + l2 * (v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
  const double removed = power(planned, v) - power(out, v);  // W taken out of the plan
  if (speed2 > 0 && removed > 0) alpha_ = removed / speed2;
  if (removed > 0) dissipated_ += removed * dt;
  ++active_ticks_;
  return out;
}

Wrench PassivityController::control(const Wrench& previous, const Wrench& planned,
                                    const double v[6], double dt, double force_step,
                                    double torque_step, const DeviceLimits& limits) {
  if (settings_.rate_limited)
    return limit(previous, planned, v, dt, force_step, torque_step, limits);
  return saturate(planned + damping(planned, v, dt), limits);
}

PassivityController::~PassivityController() {  // DEBUG
  if (std::getenv("PC_DEBUG"))
    std::fprintf(stderr, "PCDBG reserve %llu plain %llu none %llu\n",
                 static_cast<unsigned long long>(stat_reserve_), static_cast<unsigned long long>(stat_plain_),
                 static_cast<unsigned long long>(stat_none_));
}

double PassivityController::worstNextEnergy(const Wrench& w, const double v[6], double dt) const {
  const double m = settings_.misprediction_margin;
  return energy_ - settings_.energy_tolerance + power(w, v) * dt +
         m * dt * (change_bound_[0] * norm3(w.force) + change_bound_[1] * norm3(w.torque));
}

Wrench PassivityController::damping(const Wrench& planned, const double v[6], double dt) {
  alpha_ = 0;
  if (!settings_.enabled || !(dt > 0)) return Wrench{};
  const double l2 = settings_.length_scale * settings_.length_scale;
  const double speed2 =
      v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + l2 * (v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
  const double predicted = energy_ - settings_.energy_tolerance + power(planned, v) * dt;
  const double worst = worstNextEnergy(planned, v, dt);
  if (!(worst > 0) || !(speed2 > settings_.min_speed * settings_.min_speed)) return Wrench{};
  // The wrench nearest the plan (metric |df|^2 + |dtau|^2 / l^2) whose worst next energy is
  // <= 0: for a multiplier mu, each part is the plan with a damping -mu/2 (v, l^2 omega),
  // shrunk toward zero by mu/2 times its change bound (the KKT point of the projection onto
  // the convex set worstNextEnergy <= 0); mu by bisection (the worst energy falls with mu).
  const double m = settings_.misprediction_margin;
  auto part = [&](const Vec3& p, const Vec3& u, double scale, double bound, double mu) {
    const Vec3 y{p.x - 0.5 * mu * scale * u.x, p.y - 0.5 * mu * scale * u.y,
                 p.z - 0.5 * mu * scale * u.z};
    const double n = norm3(y), cut = 0.5 * mu * scale * m * bound;
    if (!(n > cut)) return Vec3{};
    const double keep = 1 - cut / n;
    return Vec3{keep * y.x, keep * y.y, keep * y.z};
  };
  auto at = [&](double mu) {
    return Wrench{part(planned.force, {v[0], v[1], v[2]}, 1.0, change_bound_[0], mu),
                  part(planned.torque, {v[3], v[4], v[5]}, l2, change_bound_[1], mu)};
  };
  Wrench out;
  if (m == 0) {
    const double a = predicted / (speed2 * dt);
    out = Wrench{{planned.force.x - a * v[0], planned.force.y - a * v[1], planned.force.z - a * v[2]},
                 {planned.torque.x - a * l2 * v[3], planned.torque.y - a * l2 * v[4],
                  planned.torque.z - a * l2 * v[5]}};
    ++stat_plain_;
  } else {
    double hi = 2 * worst / (speed2 * dt);
    int k = 0;
    for (; k < 200 && worstNextEnergy(at(hi), v, dt) > 0; ++k)
      hi *= 2;
    if (k == 200) {
      // Even the wrench cut to zero leaves a debt (E_obs > 0 after a motion beyond the bounds):
      // the plain dead-beat damping of it.
      const double debt = std::max(energy_ - settings_.energy_tolerance, 0.0);
      const double a = debt / (speed2 * dt);
      out = Wrench{{-a * v[0], -a * v[1], -a * v[2]}, {-a * l2 * v[3], -a * l2 * v[4], -a * l2 * v[5]}};
      ++stat_plain_;
    } else {
      double lo = 0;
      for (int j = 0; j < 60; ++j) {
        const double mid = 0.5 * (lo + hi);
        (worstNextEnergy(at(mid), v, dt) > 0 ? lo : hi) = mid;
      }
      out = at(hi);
      ++stat_reserve_;
    }
  }
  const Wrench change = out + (-1.0) * planned;
  const double removed = -power(change, v);
  double alpha = removed > 0 ? removed / speed2 : 0.0;
  if (removed <= 0) ++stat_none_;
  alpha_ = alpha;
  if (!isFinite(change)) {
    alpha_ = 0;
    return Wrench{};
  }
  dissipated_ += std::max(removed, 0.0) * dt;
  ++active_ticks_;
  return change;
}

void PassivityController::observe(const double v[6], double dt, bool holding) {
  if (!holding) {
    energy_ = 0;
    held_ = Wrench{};
    speed_bound_[0] = speed_bound_[1] = 0;
    change_bound_[0] = change_bound_[1] = 0;
    have_v_ = false;
    return;
  }
  // The speed bounds: the peak speeds of the last speed_hold_time or so (an oscillation's
  // amplitude, also at its turning points, where the speed passes through zero).
  const double decay = dt > 0 ? std::exp(-dt / settings_.speed_hold_time) : 1.0;
  const double lin = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  const double ang = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5]);
  if (std::isfinite(lin)) speed_bound_[0] = std::max(lin, decay * speed_bound_[0]);
  if (std::isfinite(ang)) speed_bound_[1] = std::max(ang, decay * speed_bound_[1]);
  if (have_v_) {
    const double dl = std::sqrt((v[0] - last_v_[0]) * (v[0] - last_v_[0]) +
                                (v[1] - last_v_[1]) * (v[1] - last_v_[1]) +
                                (v[2] - last_v_[2]) * (v[2] - last_v_[2]));
    const double da = std::sqrt((v[3] - last_v_[3]) * (v[3] - last_v_[3]) +
                                (v[4] - last_v_[4]) * (v[4] - last_v_[4]) +
                                (v[5] - last_v_[5]) * (v[5] - last_v_[5]));
    if (std::isfinite(dl)) change_bound_[0] = std::max(dl, decay * change_bound_[0]);
    if (std::isfinite(da)) change_bound_[1] = std::max(da, decay * change_bound_[1]);
  }
  for (int k = 0; k < 6; ++k)
    last_v_[k] = std::isfinite(v[k]) ? v[k] : 0.0;
  have_v_ = true;
  const double delta = power(held_, v) * dt;
  if (std::isfinite(delta)) energy_ += delta;
  if (energy_ > max_energy_) max_energy_ = energy_;
}

}  // namespace torsion::device
