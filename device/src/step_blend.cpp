#include "torsion/device/step_blend.h"

#include <cmath>

namespace torsion::device {

void StepBlend::update(const Wrench& jump, double dt) {
  if (!enabled()) return;
  // Exact discretisation of the first-order low-pass: the step is taken in whole, then the
  // offset holding it back decays over the tick.
  const double keep = dt > 0 ? std::exp(-2 * M_PI * cutoff_hz_ * dt) : 1.0;
  const double in[6] = {jump.force.x,  jump.force.y,  jump.force.z,
                        jump.torque.x, jump.torque.y, jump.torque.z};
  double* out[6] = {&offset_.force.x,  &offset_.force.y,  &offset_.force.z,
                    &offset_.torque.x, &offset_.torque.y, &offset_.torque.z};
  for (int k = 0; k < 6; ++k) {
    const double next = keep * (*out[k] - in[k]);
    *out[k] = std::isfinite(next) ? next : 0.0;
  }
}

}  // namespace torsion::device
