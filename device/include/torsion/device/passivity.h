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
// Controller (impedance causality: the twist comes in, the wrench goes out). At tick n, for the
// wrench W_plan the loop is about to send,
//     E_pre = E_obs(n-1) + W_plan . v(n) dt;
//     E_pre > 0 and |v|_w > min_speed:  alpha = E_pre / (|v|_w^2 dt),
//                                        W = W_plan - alpha (v_lin, l^2 v_ang)
// with |v|_w^2 = |v_lin|^2 + l^2 |v_ang|^2 and l = `length_scale` (the one damping coefficient
// alpha, N s/m, acts on rotation as alpha l^2, N m s/rad). Then W . v dt = E_pre - alpha |v|_w^2
// dt brings E_obs(n) to exactly 0: the controller removes the energy generated and no more, so
// it stays off (alpha = 0) for a passive rendering and does not change what a slow, quasi-static
// motion feels. The haptic loop adds the damping after the safety filter's rate limit (it only
// ever opposes the motion) and saturates the sum at the device's limits; the observer books the
// wrench actually written, so what saturation holds back is caught at the next tick.
//
// The port energy restarts at 0 whenever the hand holds nothing (a new grab is a new contact).

#include <cstdint>
#include <limits>
#include <string>

#include "torsion/device/device_types.h"

namespace torsion::device {

struct PassivitySettings {
  bool enabled = true;        ///< the controller; the observer always runs
  double length_scale = 0.1;  ///< m, l above: rotational damping alpha l^2 for linear alpha
  double min_speed = 1e-6;    ///< m/s of |v|_w below which no damping is added (alpha -> inf)
  /// N s/m, largest alpha (rotation: alpha l^2); infinity: none. A bound leaves some generated
  /// energy for the following ticks instead of a damping spike at small speeds.
  double max_alpha = std::numeric_limits<double>::infinity();

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

class PassivityController {
 public:
  explicit PassivityController(const PassivitySettings& settings = {}) : settings_(settings) {}

  /// The damping wrench to add to `planned` (the wrench about to be written) for twist `v`
  /// (linear m/s, angular rad/s) over `dt`; zero when the controller is off or not needed.
  Wrench damping(const Wrench& planned, const double v[6], double dt);
  /// Books the work of the wrench written at the previous tick (held by the device since) over
  /// the motion `v` dt that just happened. `holding`: a patch is grabbed with force on (else the
  /// port energy restarts at 0 and the held wrench is forgotten).
  void observe(const double v[6], double dt, bool holding);
  /// The wrench actually written this tick; observe() books it at the next tick.
  void written(const Wrench& wrench) { held_ = wrench; }

  double portEnergy() const { return energy_; }                ///< J, E_obs (<= 0 when passive)
  double maxPortEnergy() const { return max_energy_; }         ///< J, largest E_obs seen
  double alpha() const { return alpha_; }                      ///< N s/m, this tick's damping
  double dissipated() const { return dissipated_; }            ///< J, sum alpha |v|_w^2 dt so far
  std::uint64_t activeTicks() const { return active_ticks_; }  ///< ticks with alpha > 0
  const PassivitySettings& settings() const { return settings_; }

 private:
  PassivitySettings settings_;
  Wrench held_;
  double energy_ = 0;
  double max_energy_ = 0;
  double alpha_ = 0;
  double dissipated_ = 0;
  std::uint64_t active_ticks_ = 0;
};

/// Power W . v (W) of a wrench on a twist (linear m/s, angular rad/s).
double power(const Wrench& w, const double v[6]);

}  // namespace torsion::device
