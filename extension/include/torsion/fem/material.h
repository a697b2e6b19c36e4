#pragma once
// Linear elastic material of a corotational FEM body, SI units.

#include "torsion/result.h"

namespace torsion {

struct Material {
  double youngs_modulus = 1e5;  ///< E, Pa
  double poisson_ratio = 0.3;   ///< nu, in [0, 0.5)
  double density = 1000;        ///< rho, kg/m^3
  /// Rayleigh damping C = alpha M + beta K: alpha in 1/s (drag on every node, damps rigid motion
  /// too), beta in s (damps deformation rates only).
  double mass_damping = 0.0;
  double stiffness_damping = 0.01;

  /// Lame's first parameter lambda = E nu / ((1 + nu)(1 - 2 nu)), Pa.
  double lambda() const {
    return youngs_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio));
  }
  /// Shear modulus mu = G = E / (2 (1 + nu)), Pa.
  double mu() const { return youngs_modulus / (2 * (1 + poisson_ratio)); }

  /// Error naming the field when a value is out of its physical range.
  Status validate() const;
};

}  // namespace torsion
