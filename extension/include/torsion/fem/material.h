#pragma once
// Linear elastic material of a corotational FEM body, SI units.

#include <optional>
#include <string>

#include "torsion/result.h"

namespace torsion {

/// How a tet4 body measures the volume change its pressure responds to (fem/nodal_pressure.h).
enum class VolumetricStrain {
  /// Each tet its own (one-point tet4). Linear tets lock as nu -> 0.5: a body of N nodes has about
  /// 5 N tets, each a volume constraint, against 3 N degrees of freedom.
  kPerElement,
  /// Averaged over the tets around each node (average nodal pressure, Bonet & Burton 1998): one
  /// volume constraint per node, so nearly incompressible tet4 bodies do not lock. tet4 only
  /// (quadratic tets do not lock; FemModel::create refuses the combination).
  kNodalAverage,
};
/// "element" or "nodal_average" (the scene key's values).
const char* toString(VolumetricStrain kind);
std::optional<VolumetricStrain> parseVolumetricStrain(const std::string& name);

/// The constitutive law of a body (docs/materials.md). The corotated linear law steps with one
/// linearised backward-Euler solve; the hyperelastic laws (tet4 and tet10, per-element
/// volumetric strain only) with a Newton solve of the step's incremental potential
/// (solve/implicit_stepper.h).
enum class MaterialLaw {
  kCorotated,         ///< corotated linear elasticity (Mueller & Gross 2004), the default
  kStableNeoHookean,  ///< stable neo-Hookean (Smith, de Goes & Kim 2018), no log term
  kMooneyRivlin,      ///< compressible Mooney-Rivlin, C2 / (C1 + C2) = mooney_rivlin_c2_fraction
};
/// "corotated", "stable_neo_hookean" or "mooney_rivlin" (the scene key's values).
const char* toString(MaterialLaw law);
std::optional<MaterialLaw> parseMaterialLaw(const std::string& name);

struct Material {
  double youngs_modulus = 1e5;  ///< E, Pa
  double poisson_ratio = 0.3;   ///< nu, in [0, 0.5)
  double density = 1000;        ///< rho, kg/m^3
  /// Rayleigh damping C = alpha M + beta K: alpha in 1/s (drag on every node, damps rigid motion
  /// too), beta in s (damps deformation rates only).
  double mass_damping = 0.0;
  double stiffness_damping = 0.01;
  /// Per element (default) or averaged over nodes: set kNodalAverage for tet4 bodies with nu
  /// above about 0.4 (docs/validation.md, "Nearly incompressible tet4").
  VolumetricStrain volumetric_strain = VolumetricStrain::kPerElement;
  /// Volume barrier against inverted tets (fem/volume_barrier.h): an energy that is exactly zero
  /// while every tet keeps more than barrier_threshold of its rest volume (J = det F), so it
  /// changes nothing at ordinary strains. J0 in [0, 1); 0 turns it off.
  double barrier_threshold = 0.3;
  /// The barrier's pressure at J = 0 in units of the bulk modulus (k = barrier_stiffness kappa).
  double barrier_stiffness = 30.0;
  /// The constitutive law; E and nu give its small-strain moduli whichever it is.
  MaterialLaw law = MaterialLaw::kCorotated;
  /// Mooney-Rivlin only: C2 / (C1 + C2) in [0, 1] (0: neo-Hookean at J = 1); needs nu > 0 at 1.
  double mooney_rivlin_c2_fraction = 0.5;

  /// True for the laws stepped by Newton's method (everything but kCorotated).
  bool hyperelastic() const { return law != MaterialLaw::kCorotated; }

  /// Lame's first parameter lambda = E nu / ((1 + nu)(1 - 2 nu)), Pa.
  double lambda() const {
    return youngs_modulus * poisson_ratio / ((1 + poisson_ratio) * (1 - 2 * poisson_ratio));
  }
  /// Shear modulus mu = G = E / (2 (1 + nu)), Pa.
  double mu() const { return youngs_modulus / (2 * (1 + poisson_ratio)); }
  /// Bulk modulus kappa = lambda + 2 mu / 3 = E / (3 (1 - 2 nu)), Pa.
  double bulkModulus() const { return youngs_modulus / (3 * (1 - 2 * poisson_ratio)); }

  /// Error naming the field when a value is out of its physical range.
  Status validate() const;
};

}  // namespace torsion
