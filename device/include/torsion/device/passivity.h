#pragma once
// Time-domain passivity at the device port (Hannaford & Ryu 2002, "Time-domain passivity
// control of haptic interfaces"): an observer that books the energy the rendering has given the
// user's hand, and a controller that adds exactly the damping needed to take it back.
//
// Sign convention. The wrench W is what the device applies to the hand (docs/haptics.md); the
// twist v = (linear m/s, angular rad/s) is the hand's, from successive device poses. The power
// the rendering delivers to the hand is W . v (force . velocity + torque . angular velocity,
// watts), and the port energy
//     E_obs(n) = sum_{k <= n} W_out(k) . v(k) dt_k
// is the energy the virtual environment has given the operator so far. A passive environment
// only gives back what it was given: E_obs <= 0 at all times (a spring pressed in holds
// -E_obs = K x^2 / 2 and returns it). E_obs > 0 is energy the coupling generated (delay, sample
// and hold, a stale simulation wrench), the source of the growing buzz of an unstable coupling.
//
// Controller (impedance causality: the twist comes in, the wrench goes out). At tick n the
// wrench W(n) is chosen, then held while the hand moves: its work W(n) . v(n+1) dt is booked at
// the next tick and depends on a motion not yet known. No wrench but zero is passive against
// every motion, so a strict controller must bound the coming motion. Three kinds.
//
// Dead-beat damper with a misprediction reserve (the default: misprediction_margin > 0). The
// coming twist is predicted as u = 2 v(n) - v(n-1) (the last tick's change goes on), and the
// error of that prediction bounded by b = the peak error it had over about the last
// speed_hold_time (decaying), per part (b_f m/s, b_t rad/s). With m = misprediction_margin,
//     G(W) = E_obs(n) - energy_tolerance + W . u dt + m dt (b_f |f| + b_t |tau|)     (J)
// is E_obs after the tick at the worst twist within m b of u. G(W_plan) <= 0: W = W_plan, the
// controller does nothing. Else W = the wrench nearest W_plan with G(W) <= 0 (metric
// |df|^2 + |dtau|^2 / l^2; the set is convex and holds W = 0 while E_obs <= 0): each part of
// the plan, with a damping of the predicted motion mu/2 (u_lin, l^2 u_ang) added, shrunk toward
// zero by mu/2 times its share m b (the KKT point; mu by bisection). Then E_obs <= 0 after the
// tick whenever the hand's twist stays within m b of the prediction, to rounding. A motion
// beyond the bound leaves a debt (E_obs > 0), damped away at the next ticks. The correction
// goes on after the safety filter's rate limit: the written wrench steps while it acts (the
// step damps the predicted motion and shrinks the wrench toward zero; docs/haptics.md).
//
// Plain dead-beat damper (Hannaford & Ryu; misprediction_margin = 0). For W_plan and the last
// twist v(n),
//     E_pre = E_obs(n) - energy_tolerance + W_plan . v(n) dt;
//     E_pre > 0 and |v|_w > min_speed:  alpha = E_pre / (|v|_w^2 dt),
//                                        W = W_plan - alpha (v_lin, l^2 v_ang)
// with |v|_w^2 = |v_lin|^2 + l^2 |v_ang|^2 and l = `length_scale` (the one damping coefficient
// alpha, N s/m, acts on rotation as alpha l^2, N m s/rad): E_obs after the tick is exactly
// energy_tolerance if the motion goes on as in the last tick, and exceeds it by the
// misprediction W . (v(n+1) - v(n)) dt otherwise.
//
// Rate-limited energy reserve (`rate_limited: true`). The wrench written to the device
// changes by at most the safety filter's rate limit per tick (r_f N/s, r_t N m/s), damping
// included, so the controller cannot take a large amount of energy back in one tick: it must
// never hand out more of the reserve -E_obs than it could still stop. For a wrench W = (f, tau)
// the reserve need is
//     N(W) = E_obs(n) - energy_tolerance + W . v(n) dt + |f|^2 s_f / (2 r_f)
//            + |tau|^2 s_t / (2 r_t)     (J)
// the energy already given, the work of W over the coming tick, and the most that ramping f and
// tau down to zero at the rate limit (|f| / r_f, |tau| / r_t seconds) can give out while the
// hand moves at up to s_f m/s and s_t rad/s. The speed bounds s are the peak speeds of about the
// last `speed_hold_time` (decaying; an oscillation's speed passes through zero at each turning
// point, its amplitude does not) times `speed_margin` (the wrench being ramped down keeps
// accelerating the hand). Each tick, with W_prev the wrench written at the last tick and W_plan
// the safety filter's rate-limited step from it toward the rendering:
//   - N(W_plan) <= 0: W = W_plan, the controller does nothing;
//   - else the brake, W_brake = the wrench within the rate limit of W_prev with the least N
//     (toward N's minimiser -v dt r / s, i.e. toward zero, then against the motion); W = the
//     point of the segment W_plan -> W_brake nearest W_plan with N <= 0 (W_brake when none).
// Both ends lie in the rate-limit ball around W_prev, so every point between does: the output
// never steps by more than the rate limit, and the energy is taken back over several ticks. An
// energy debt (E_obs > 0, after a motion faster than the bounds) keeps N > 0, so the brake holds
// the output small and then damps, at the rate limit, until it is repaid. A slow, quasi-static
// motion into a spring keeps a reserve of the spring's stored energy and is left alone.
//
// Either way the observer books the wrench actually written, so what saturation holds back is
// caught at the next tick, and alpha() reports the damping as an equivalent coefficient: the
// power taken out of W_plan over |v|_w^2 (N s/m).
//
// The port energy restarts at 0 whenever the hand holds nothing (a new grab is a new contact).

#include <cstdint>
#include <limits>
#include <string>

#include "torsion/device/device_types.h"

namespace torsion::device {

struct PassivitySettings {
  bool enabled = true;  ///< the controller; the observer always runs
  /// The energy-reserve controller, which plans within the rate limit (above; the default).
  /// false: the dead-beat damper, whose correction the safety filter's rate limit then spreads
  /// over several ticks, so that its one-tick guarantee no longer holds (docs/haptics.md
  /// compares them): the rate limit is the last stage before the device whatever the kind.
  bool rate_limited = true;
  /// Dead-beat damper: m above, the factor on the bound of the twist's prediction error the
  /// controller keeps a reserve for. 0: the plain dead-beat damper (no reserve, E_obs exceeds 0
  /// by each tick's misprediction). 3 by default: E_obs <= 0 to rounding on every validation
  /// run (docs/haptics.md, "Passivity"; 2 lets mispredictions of 0.2 mJ through).
  double misprediction_margin = 3;
  /// s: how long the speed bound (rate-limited controller) and the bound of the twist's
  /// prediction error (dead-beat damper) hold a peak (they decay as exp(-t / speed_hold_time));
  /// about an oscillation period of the hand on the device.
  double speed_hold_time = 0.1;
  /// Rate-limited controller: the speed bound's factor. The wrench being ramped down keeps
  /// accelerating the hand meanwhile, so the speed while braking exceeds the one measured.
  double speed_margin = 2;
  double length_scale = 0.1;  ///< m, l above: rotational damping alpha l^2 for linear alpha
  /// J the port may hold above 0 before either controller acts (E_obs <= energy_tolerance is
  /// its target instead of 0). A stiff sampled rendering's own excess can be a few microjoules;
  /// acting on it makes the controller chatter and soften what the hand feels, while a
  /// tolerance lets a larger misprediction through on a delayed one (docs/haptics.md,
  /// "Passivity", measures both). 0: the strict controller.
  double energy_tolerance = 0;
  /// m/s of |v|_w below which the plain dead-beat damper adds no damping (alpha -> inf)
  double min_speed = 1e-6;
  /// Plain dead-beat damper: N s/m, largest alpha (rotation: alpha l^2); infinity: none. A
  /// bound leaves some generated energy for the following ticks instead of a damping spike.
  double max_alpha = std::numeric_limits<double>::infinity();

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

class PassivityController {
 public:
  explicit PassivityController(const PassivitySettings& settings = {}) : settings_(settings) {}

  /// Dead-beat damper: the change to add to `planned` (the wrench about to be written) after
  /// the twist `v` (linear m/s, angular rad/s) of the tick of `dt` just observed: a damping of
  /// the predicted motion and, with the reserve, a shrink toward zero; zero when the
  /// controller is off or not needed.
  Wrench correction(const Wrench& planned, const double v[6], double dt);
  /// Rate-limited energy reserve: the wrench to write this tick. `previous`: the wrench written
  /// at the last tick; `planned`: the rate-limited step from it toward the rendering (within
  /// `force_step` N and `torque_step` N m of `previous`); the result is too, and within
  /// `limits`. `planned` itself when the controller is off or not needed.
  Wrench limit(const Wrench& previous, const Wrench& planned, const double v[6], double dt,
               double force_step, double torque_step, const DeviceLimits& limits);
  /// The loop's choice: limit() when settings().rate_limited, else planned + correction(),
  /// saturated.
  Wrench control(const Wrench& previous, const Wrench& planned, const double v[6], double dt,
                 double force_step, double torque_step, const DeviceLimits& limits);
  /// Books the work of the wrench written at the previous tick (held by the device since) over
  /// the motion `v` dt that just happened. `holding`: a patch is grabbed with force on (else the
  /// port energy restarts at 0 and the held wrench is forgotten).
  void observe(const double v[6], double dt, bool holding);
  /// The wrench actually written this tick; observe() books it at the next tick. When ticks
  /// pass without an observation (device readings the loop refused), the motion observed next
  /// is shared evenly among the wrenches written meanwhile: each was held for its share of it.
  void written(const Wrench& wrench);

  double portEnergy() const { return energy_; }         ///< J, E_obs (<= 0 when passive)
  double maxPortEnergy() const { return max_energy_; }  ///< J, largest E_obs seen
  double alpha() const { return alpha_; }               ///< N s/m, this tick's damping (equivalent)
  double dissipated() const { return dissipated_; }     ///< J, power taken out of W_plan, summed
  std::uint64_t activeTicks() const { return active_ticks_; }  ///< ticks it changed the wrench
  const PassivitySettings& settings() const { return settings_; }

 private:
  /// J: E_obs plus the work of `w` over the coming tick plus what ramping it to zero at the
  /// rates (N/s, N m/s) could give out at the speed bounds; > 0: not covered by the reserve.
  double reserveNeed(const Wrench& w, const double v[6], double dt, double force_rate,
                     double torque_rate) const;
  /// J: G(w) above, E_obs after the coming tick with `w` held at the worst twist within
  /// misprediction_margin times the change bounds of the predicted twist `v`.
  double worstNextEnergy(const Wrench& w, const double v[6], double dt) const;

  PassivitySettings settings_;
  double speed_bound_[2] = {0, 0};   // m/s, rad/s: peak speeds, decaying
  double change_bound_[2] = {0, 0};  // m/s, rad/s: peak prediction errors of the twist, decaying
  double last_v_[6] = {};            // v(n), then v(n-1): the twists the prediction starts from
  double prev_v_[6] = {};
  int have_v_ = 0;      // how many of them are known (0-2)
  Wrench held_;         // the last wrench written: the device holds it until the next
  Wrench held_sum_;     // the wrenches written since the last observe(), summed
  int held_count_ = 0;  // how many
  double energy_ = 0;
  double max_energy_ = 0;
  double alpha_ = 0;
  double dissipated_ = 0;
  std::uint64_t active_ticks_ = 0;
};

/// Power W . v (W) of a wrench on a twist (linear m/s, angular rad/s).
double power(const Wrench& w, const double v[6]);

}  // namespace torsion::device
