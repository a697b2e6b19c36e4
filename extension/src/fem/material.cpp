#include "torsion/fem/material.h"

#include <cmath>
#include <string>

#include "torsion/format_number.h"

namespace torsion {

const char* toString(VolumetricStrain kind) {
  return kind == VolumetricStrain::kNodalAverage ? "nodal_average" : "element";
}

std::optional<VolumetricStrain> parseVolumetricStrain(const std::string& name) {
  if (name == "element") return VolumetricStrain::kPerElement;
  if (name == "nodal_average") return VolumetricStrain::kNodalAverage;
  return std::nullopt;
}

const char* toString(MaterialLaw law) {
  switch (law) {
    case MaterialLaw::kCorotated:
      return "corotated";
    case MaterialLaw::kStableNeoHookean:
      return "stable_neo_hookean";
    case MaterialLaw::kMooneyRivlin:
      return "mooney_rivlin";
  }
  return "?";
}

std::optional<MaterialLaw> parseMaterialLaw(const std::string& name) {
  for (MaterialLaw law :
       {MaterialLaw::kCorotated, MaterialLaw::kStableNeoHookean, MaterialLaw::kMooneyRivlin}) {
    if (name == toString(law)) return law;
  }
  return std::nullopt;
}

Status Material::validate() const {
  auto bad = [](const char* field, double value, const char* rule) {
    return Error{std::string("material: ") + field + " = " + formatNumber(value) + ": " + rule};
  };
  if (!(std::isfinite(youngs_modulus) && youngs_modulus > 0))
    return bad("youngs_modulus", youngs_modulus, "must be > 0 Pa");
  if (!(std::isfinite(poisson_ratio) && poisson_ratio >= 0 && poisson_ratio < 0.5))
    return bad("poisson_ratio", poisson_ratio, "must be in [0, 0.5)");
  if (!(std::isfinite(density) && density > 0))
    return bad("density", density, "must be > 0 kg/m^3");
  if (!(std::isfinite(mass_damping) && mass_damping >= 0))
    return bad("mass_damping", mass_damping, "must be >= 0 1/s");
  if (!(std::isfinite(stiffness_damping) && stiffness_damping >= 0))
    return bad("stiffness_damping", stiffness_damping, "must be >= 0 s");
  if (!(std::isfinite(barrier_threshold) && barrier_threshold >= 0 && barrier_threshold < 1))
    return bad("barrier_threshold", barrier_threshold, "must be in [0, 1)");
  if (!(std::isfinite(barrier_stiffness) && barrier_stiffness >= 0))
    return bad("barrier_stiffness", barrier_stiffness, "must be >= 0");
  const double c2 = mooney_rivlin_c2_fraction;
  if (!(std::isfinite(c2) && c2 >= 0 && c2 <= 1))
    return bad("mooney_rivlin_c2_fraction", c2, "must be in [0, 1]");
  if (law == MaterialLaw::kMooneyRivlin && c2 == 1 && poisson_ratio == 0) {
    return bad("mooney_rivlin_c2_fraction", c2,
               "must be below 1 at poisson_ratio = 0 (the volumetric modulus lambda + 2 C1 would "
               "be 0)");
  }
  return Ok{};
}

}  // namespace torsion
