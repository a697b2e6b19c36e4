#include "arithmetic_bounds.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/format_number.h"

namespace torsion::scene {

namespace {
std::string g(double value) {
  return formatNumber(value);
}
}  // namespace

Status checkGravity(const Eigen::Vector3d& gravity) {
  const double magnitude = gravity.stableNorm();  // norm() would overflow to inf past 1e154
  if (magnitude <= kMaxGravity) return Ok{};
  return Error{"magnitude " + g(magnitude) + " m/s^2 is above the bound " + g(kMaxGravity) +
               " m/s^2 (forces and their squares must stay finite)"};
}

Status checkStiffnessRatio(const Material& material, const TetMesh& mesh, double dt) {
  double shortest_sq = std::numeric_limits<double>::infinity();
  const std::vector<Eigen::Vector3d>& x = mesh.restPositions();
  for (const auto& tet : mesh.tets()) {
    for (size_t a = 0; a < tet.size(); ++a) {
      for (size_t b = a + 1; b < tet.size(); ++b) {
        shortest_sq = std::min(
            shortest_sq,
            (x[static_cast<size_t>(tet[a])] - x[static_cast<size_t>(tet[b])]).squaredNorm());
      }
    }
  }
  const double ratio = material.youngs_modulus * dt * dt / (material.density * shortest_sq);
  if (ratio <= kMaxStiffnessRatio) return Ok{};
  return Error{"material: E dt^2 / (rho h^2) = " + g(ratio) + " (E " + g(material.youngs_modulus) +
               " Pa, dt " + g(dt) + " s, rho " + g(material.density) + " kg/m^3, shortest edge h " +
               g(std::sqrt(shortest_sq)) + " m) is above the bound " + g(kMaxStiffnessRatio) +
               ": the step's arithmetic would overflow"};
}

}  // namespace torsion::scene
