#include "torsion/device/local_wrench_model.h"

#include <algorithm>
#include <cmath>

#include "torsion/device/pose_math.h"

namespace torsion::device {

bool predicts(const SimulationWrench& simulated) {
  for (double k : simulated.stiffness)
    if (k != 0) return true;
  return false;
}

Wrench renderLocalModel(const SimulationWrench& simulated, const Pose& pose, const double twist[6],
                        const CouplingDamper& damper, const DeviceLimits* bound) {
  double delta[6];
  poseDifference(simulated.pose, pose, delta);
  double prediction[6] = {};
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c)
      prediction[r] += simulated.stiffness[6 * r + c] * delta[c];
  if (bound != nullptr) {
    const Vec3 force = clampNorm({prediction[0], prediction[1], prediction[2]}, bound->max_force);
    const Vec3 torque = clampNorm({prediction[3], prediction[4], prediction[5]}, bound->max_torque);
    const double clamped[6] = {force.x, force.y, force.z, torque.x, torque.y, torque.z};
    std::copy(clamped, clamped + 6, prediction);
  }
  const double w[6] = {simulated.wrench.force.x + prediction[0] - damper.linear * twist[0],
                       simulated.wrench.force.y + prediction[1] - damper.linear * twist[1],
                       simulated.wrench.force.z + prediction[2] - damper.linear * twist[2],
                       simulated.wrench.torque.x + prediction[3] - damper.angular * twist[3],
                       simulated.wrench.torque.y + prediction[4] - damper.angular * twist[4],
                       simulated.wrench.torque.z + prediction[5] - damper.angular * twist[5]};
  return {{w[0], w[1], w[2]}, {w[3], w[4], w[5]}};
}

const double* TwistEstimator::update(const Pose& pose, double time) {
  const double dt = time - previous_time_;
  if (have_previous_ && dt > 0 && std::isfinite(dt)) {
    double delta[6];
    poseDifference(previous_, pose, delta);
    // Exact discretisation of a first-order low-pass: a = 1 - exp(-2 pi fc dt).
    const double a = 1 - std::exp(-2 * M_PI * cutoff_hz_ * dt);
    for (int k = 0; k < 6; ++k) {
      const double raw = delta[k] / dt;
      if (std::isfinite(raw)) twist_[k] += a * (raw - twist_[k]);
    }
  } else if (!have_previous_) {
    for (double& v : twist_)
      v = 0;
  }
  have_previous_ = true;
  previous_ = pose;
  previous_time_ = time;
  return twist_;
}

}  // namespace torsion::device
