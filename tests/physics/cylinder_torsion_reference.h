#pragma once
// The exact torsion of a compressible hyperelastic cylinder held at its length, reduced to one
// dimension and solved to high accuracy: the reference the FEM twist is checked against.
//
// Helical symmetry makes the semi-inverse field x = rho(R) e_r(Theta + psi Z) + lambda Z e_z
// exact for any isotropic law at a given length (lambda = 1: held at its length; the lambda with
// N = 0: the free bar): in the orthonormal bases (E_R, E_Theta, E_Z) and (e_r, e_theta, e_z)
//   F = [[rho', 0, 0], [0, rho / R, rho psi], [0, 0, lambda]],
// C has no (R, Z) or (R, Theta) entries, so neither has the stress: the theta and z equilibrium
// equations hold identically and only the radial one is left. It is the stationarity of the
// energy per unit length 2 pi int_0^a Psi(F) R dR over rho(R) (rho(0) = 0, R = a free), solved
// here with linear elements in R, midpoint quadrature and Newton's method on the exact tangent
// (firstPiolaDerivative). From the solution, the end loads that hold the twist (first Piola
// tractions P E_Z on the end face):
//   T = 2 pi int rho P_theta,Z R dR   (axial torque)      N = 2 pi int P_z,Z R dR   (axial force)
// Incompressible neo-Hookean (Rivlin 1949): rho = R, T = mu pi a^4 psi / 2 = mu J psi and
// N = -mu pi a^4 psi^2 / 4 (compressive: the free bar would lengthen, the Poynting effect); an
// incompressible Mooney-Rivlin law gives N = -pi a^4 psi^2 (C1 / 2 + C2).

#include <Eigen/Dense>
#include <cmath>

#include "torsion/fem/hyperelastic.h"

namespace torsion::test {

struct TorsionLoads {
  double torque = 0;             ///< N m, applied about +z at the end z = L
  double axial_force = 0;        ///< N, applied along +z at that end (negative: compressive)
  double max_radial_change = 0;  ///< max |rho / R - 1|
};

// `twist_rate` is per unit rest length; `axial_stretch` the bar's length over its rest length (1:
// held at its length).
template <class Law>
TorsionLoads exactTorsion(const Law& law, double radius, double twist_rate, int intervals = 400,
                          double axial_stretch = 1.0) {
  const int n = intervals;
  const double h = radius / n;
  // rho at nodes 1..n (node 0 is the axis, rho = 0).
  Eigen::VectorXd rho(n);
  for (int i = 0; i < n; ++i)
    rho[i] = (i + 1) * h;
  auto gradientOf = [&](int m, double r, double dr) {
    Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
    F(0, 0) = dr;
    F(1, 1) = r / ((m + 0.5) * h);
    F(1, 2) = r * twist_rate;
    F(2, 2) = axial_stretch;
    return F;
  };
  for (int iteration = 0; iteration < 30; ++iteration) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
    for (int m = 0; m < n; ++m) {
      const double R = (m + 0.5) * h, w = 2 * M_PI * R * h;
      const double left = m == 0 ? 0.0 : rho[m - 1], right = rho[m];
      const Eigen::Matrix3d F = gradientOf(m, 0.5 * (left + right), (right - left) / h);
      const Eigen::Matrix3d P = firstPiola(law, F);
      const PiolaTangent A = firstPiolaDerivative(law, F);
      // d vec(F) / d rho_j for the element's two nodes (vec by columns: (0,0), (1,1), (1,2) are
      // entries 0, 4, 7).
      Eigen::Matrix<double, 9, 2> dF = Eigen::Matrix<double, 9, 2>::Zero();
      for (int k = 0; k < 2; ++k) {
        dF(0, k) = k == 0 ? -1.0 / h : 1.0 / h;
        dF(4, k) = 0.5 / R;
        dF(7, k) = 0.5 * twist_rate;
      }
      const Eigen::Map<const Eigen::Matrix<double, 9, 1>> p(P.data());
      const Eigen::Vector2d ge = w * dF.transpose() * p;
      const Eigen::Matrix2d He = w * dF.transpose() * A * dF;
      const int index[2] = {m - 1, m};
      for (int a = 0; a < 2; ++a) {
        if (index[a] < 0) continue;
        g[index[a]] += ge[a];
        for (int b = 0; b < 2; ++b)
          if (index[b] >= 0) H(index[a], index[b]) += He(a, b);
      }
    }
    const Eigen::VectorXd step = H.ldlt().solve(g);
    rho -= step;
    if (step.cwiseAbs().maxCoeff() < 1e-14 * radius) break;
  }
  TorsionLoads loads;
  for (int m = 0; m < n; ++m) {
    const double R = (m + 0.5) * h, w = 2 * M_PI * R * h;
    const double left = m == 0 ? 0.0 : rho[m - 1], right = rho[m];
    const double r = 0.5 * (left + right);
    const Eigen::Matrix3d P = firstPiola(law, gradientOf(m, r, (right - left) / h));
    loads.torque += w * r * P(1, 2);
    loads.axial_force += w * P(2, 2);
    loads.max_radial_change = std::max(loads.max_radial_change, std::abs(r / R - 1));
  }
  return loads;
}

}  // namespace torsion::test
