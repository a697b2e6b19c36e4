#pragma once
// Private helper: Hooke's law in Lame form, shared by the tet4 and tet10 elements
// (corotated_element.cpp, quadratic_element.cpp): both rotate a small strain's stress back to the
// deformed frame.

#include <Eigen/Core>

namespace torsion::detail {

/// sigma = 2 mu eps + lambda tr(eps) I, for a symmetric small strain eps.
inline Eigen::Matrix3d linearStress(const Eigen::Matrix3d& strain, double mu, double lambda) {
  return 2 * mu * strain + lambda * strain.trace() * Eigen::Matrix3d::Identity();
}

}  // namespace torsion::detail
