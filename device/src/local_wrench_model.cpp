#include "torsion/device/local_wrench_model.h"

#include <cmath>

#include "torsion/device/pose_math.h"

namespace torsion::device {

Wrench renderLocalModel(const SimulationWrench& simulated, const Pose& pose, const double twist[6],
                        const CouplingDamper& damper) {
  double delta[6];
  poseDifference(simulated.pose, pose, delta);
  double w[6] = {simulated.wrench.force.x,  simulated.wrench.force.y,  simulated.wrench.force.z,
                 simulated.wrench.torque.x, simulated.wrench.torque.y, simulated.wrench.torque.z};
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c)
      w[r] += simulated.stiffness[6 * r + c] * delta[c];
    w[r] -= (r < 3 ? damper.linear : damper.angular) * twist[r];
  }
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
