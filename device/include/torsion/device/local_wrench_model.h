#pragma once
// What the haptic loop renders between two simulation steps (docs/design.md section 4): the last
// simulated wrench corrected by the patch's local stiffness for the pose change since, plus a
// virtual-coupling damper that takes energy out (passivity at 1 kHz against a 30-200 Hz
// simulation):
//   W = W_sim + K_h (pose - pose_sim) - B twist
// with K_h the 6x6 of SimulationWrench::stiffness and twist the device's velocity
// (m/s, rad/s).

#include "torsion/device/device_types.h"

namespace torsion::device {

/// Virtual-coupling damper. Zero: no damping.
struct CouplingDamper {
  double linear = 0;   ///< N s/m
  double angular = 0;  ///< N m s/rad
};

/// The wrench for the device at `pose`, moving with `twist` (6: linear m/s, angular rad/s).
/// With `bound`, the prediction K_h (pose - pose_sim) is scaled down (force and torque each as a
/// vector, direction kept) to the device's max_force and max_torque: a pose far from the one
/// the simulation used (a stalled simulation, a jump of the device) cannot extrapolate a
/// linearisation into a wrench beyond what the device may render. A prediction that is not
/// finite is dropped (zero), as the device layer's limiter does (pose_math.h, clampNorm()).
Wrench renderLocalModel(const SimulationWrench& simulated, const Pose& pose, const double twist[6],
                        const CouplingDamper& damper, const DeviceLimits* bound = nullptr);

/// True when `simulated` carries a local stiffness (any entry non-zero): the loop then predicts
/// between steps from the current pose.
bool predicts(const SimulationWrench& simulated);

/// Estimates the device's twist from successive poses, low-pass filtered (first order) so that
/// the damper does not amplify sensor noise.
class TwistEstimator {
 public:
  explicit TwistEstimator(double cutoff_hz = 50) : cutoff_hz_(cutoff_hz) {}
  /// Feeds the pose at `time`; returns the filtered twist.
  const double* update(const Pose& pose, double time);
  /// The filtered twist of the last update().
  const double* twist() const { return twist_; }
  void reset() { have_previous_ = false; }

 private:
  double cutoff_hz_;
  bool have_previous_ = false;
  Pose previous_;
  double previous_time_ = 0;
  double twist_[6] = {};
};

}  // namespace torsion::device
