#include "torsion/device/passivity.h"

#include <algorithm>
#include <cmath>

#include "torsion/device/pose_math.h"
#include "torsion/device/wrench_safety.h"

namespace torsion::device {

namespace {

constexpr double kNegligibleEnergy = 1e-12;  // J

}  // namespace

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

Vec3 lerp(const Vec3& a, const Vec3& b, double u) {
  return {a.x + u * (b.x - a.x), a.y + u * (b.y - a.y), a.z + u * (b.z - a.z)};
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
  const double n = norm(v);
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
  return saturate(planned + correction(planned, v, dt), limits);
}

double PassivityController::worstNextEnergy(const Wrench& w, const double v[6], double dt) const {
  return energy_ - settings_.energy_tolerance + power(w, v) * dt +
         settings_.misprediction_margin * dt *
             (change_bound_[0] * norm(w.force) + change_bound_[1] * norm(w.torque));
}

Wrench PassivityController::correction(const Wrench& planned, const double v[6], double dt) {
  alpha_ = 0;
  if (!settings_.enabled || !(dt > 0)) return Wrench{};
  const double l2 = settings_.length_scale * settings_.length_scale;
  const double m = settings_.misprediction_margin;
  // The coming tick's twist: the last one (plain dead-beat), or the last one plus the last
  // change (the reserve: the hand's acceleration goes on; the bound covers its change).
  double u[6];
  for (int k = 0; k < 6; ++k)
    u[k] = m > 0 && have_v_ >= 2 ? 2 * v[k] - prev_v_[k] : v[k];
  const double speed2 =
      u[0] * u[0] + u[1] * u[1] + u[2] * u[2] + l2 * (u[3] * u[3] + u[4] * u[4] + u[5] * u[5]);
  const double worst = worstNextEnergy(planned, u, dt);
  // A worst case below a picojoule is rounding (the first ticks of a grab, when the hand's
  // motion is not yet known and the wrench is still fading in): left alone, so that a passive
  // rendering never wakes the controller. E_obs may then end a tick that far above 0.
  if (!(worst > (m > 0 ? kNegligibleEnergy : 0.0))) return Wrench{};
  Wrench out;
  if (m == 0) {
    // The plain dead-beat damper.
    if (!(speed2 > settings_.min_speed * settings_.min_speed)) return Wrench{};
    const double a = std::min(worst / (speed2 * dt), settings_.max_alpha);
    out = planned + Wrench{{-a * u[0], -a * u[1], -a * u[2]},
                           {-a * l2 * u[3], -a * l2 * u[4], -a * l2 * u[5]}};
  } else {
    // The wrench nearest the plan (metric |df|^2 + |dtau|^2 / l^2) with worstNextEnergy <= 0, a
    // convex set that holds W = 0 while E_obs <= 0. Its KKT point for a multiplier mu: each
    // part is the plan with a damping of the predicted motion, mu/2 (u, l^2 omega), then
    // shrunk toward zero by mu/2 times its share of the reserve (m times the change bound);
    // the worst energy falls as mu grows, so mu by bisection.
    auto part = [&](const Vec3& p, const double* w, double scale, double bound, double mu) {
      const double d = 0.5 * mu * scale;
      const Vec3 y{p.x - d * w[0], p.y - d * w[1], p.z - d * w[2]};
      const double n = norm(y), cut = d * m * bound;
      if (!(n > cut)) return Vec3{};
      const double keep = 1 - cut / n;
      return Vec3{keep * y.x, keep * y.y, keep * y.z};
    };
    // Only the parts whose own worst-case work is positive are changed (a part that cannot
    // give energy is left as planned): damping the other part's predicted motion would pay for
    // this one's risk with a kick that the prediction does not cover.
    auto partWorst = [&](const Vec3& w, const double* v_part, double bound) {
      return (w.x * v_part[0] + w.y * v_part[1] + w.z * v_part[2]) * dt + m * dt * bound * norm(w);
    };
    const bool risky[2] = {partWorst(planned.force, u, change_bound_[0]) > 0,
                           partWorst(planned.torque, u + 3, change_bound_[1]) > 0};
    auto project = [&](bool force, bool torque, Wrench* result) {
      auto at = [&](double mu) {
        return Wrench{
            force ? part(planned.force, u, 1.0, change_bound_[0], mu) : planned.force,
            torque ? part(planned.torque, u + 3, l2, change_bound_[1], mu) : planned.torque};
      };
      double hi = speed2 > 0 ? 2 * worst / (speed2 * dt) : 1.0;
      int doublings = 0;
      for (; doublings < 400 && worstNextEnergy(at(hi), u, dt) > 0; ++doublings)
        hi *= 2;
      if (doublings == 400) return false;
      double lo = 0;
      for (int k = 0; k < 64; ++k) {
        const double mid = 0.5 * (lo + hi);
        (worstNextEnergy(at(mid), u, dt) > 0 ? lo : hi) = mid;
      }
      *result = at(hi);
      return true;
    };
    if (!((risky[0] || risky[1]) && project(risky[0], risky[1], &out)) &&
        !project(true, true, &out) && speed2 > settings_.min_speed * settings_.min_speed) {
      // Not even W = 0 covers it: E_obs > 0 already, after a motion beyond the bound. Damp
      // the debt away as the plain dead-beat damper would.
      const double a = std::max(energy_ - settings_.energy_tolerance, 0.0) / (speed2 * dt);
      out = Wrench{{-a * u[0], -a * u[1], -a * u[2]},
                   {-a * l2 * u[3], -a * l2 * u[4], -a * l2 * u[5]}};
    }
  }
  const Wrench change = out + (-1.0) * planned;
  if (!isFinite(change)) return Wrench{};
  const double removed = -power(change, u);  // W taken out of the plan
  if (removed > 0) {
    alpha_ = speed2 > 0 ? removed / speed2 : 0.0;
    dissipated_ += removed * dt;
  }
  ++active_ticks_;
  return change;
}

namespace {

double partNorm(const double* v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

}  // namespace

void PassivityController::written(const Wrench& wrench) {
  held_ = wrench;
  held_sum_ = held_sum_ + wrench;
  ++held_count_;
}

void PassivityController::observe(const double v[6], double dt, bool holding) {
  if (!holding) {
    energy_ = 0;
    held_ = held_sum_ = Wrench{};
    held_count_ = 0;
    speed_bound_[0] = speed_bound_[1] = 0;
    change_bound_[0] = change_bound_[1] = 0;
    have_v_ = 0;
    return;
  }
  // The speed bounds: the peak speeds of the last speed_hold_time or so (an oscillation's
  // amplitude, also at its turning points, where the speed passes through zero).
  const double decay = dt > 0 ? std::exp(-dt / settings_.speed_hold_time) : 1.0;
  const double lin = partNorm(v), ang = partNorm(v + 3);
  if (std::isfinite(lin)) speed_bound_[0] = std::max(lin, decay * speed_bound_[0]);
  if (std::isfinite(ang)) speed_bound_[1] = std::max(ang, decay * speed_bound_[1]);
  // The change bounds: the peak error of predicting this tick's twist from the last two,
  // v(n) - (2 v(n-1) - v(n-2)), over the same time.
  if (have_v_ >= 2) {
    double error[6];
    for (int k = 0; k < 6; ++k)
      error[k] = v[k] - (2 * last_v_[k] - prev_v_[k]);
    const double el = partNorm(error), ea = partNorm(error + 3);
    if (std::isfinite(el)) change_bound_[0] = std::max(el, decay * change_bound_[0]);
    if (std::isfinite(ea)) change_bound_[1] = std::max(ea, decay * change_bound_[1]);
  }
  for (int k = 0; k < 6; ++k) {
    prev_v_[k] = last_v_[k];
    last_v_[k] = std::isfinite(v[k]) ? v[k] : 0.0;
  }
  have_v_ = std::min(have_v_ + 1, 2);
  // The mean of the wrenches held over the motion (one wrench on every tick but after refused
  // readings), each for an equal share of it; the last one when none was written since.
  const Wrench held =
      held_count_ > 0 ? (1.0 / static_cast<double>(held_count_)) * held_sum_ : held_;
  held_sum_ = Wrench{};
  held_count_ = 0;
  const double delta = power(held, v) * dt;
  if (std::isfinite(delta)) energy_ += delta;
  if (energy_ > max_energy_) max_energy_ = energy_;
}

}  // namespace torsion::device
