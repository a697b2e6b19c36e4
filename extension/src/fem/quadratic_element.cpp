#include "torsion/fem/quadratic_element.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "linear_stress.h"
#include "torsion/mesh/quadratic_tet_mesh.h"

namespace torsion {

namespace {

constexpr double kA = 0.5854101966249685;  // (5 + 3 sqrt 5) / 20
constexpr double kB = 0.1381966011250105;  // (5 - sqrt 5) / 20

// The axial vector of skew(A): skew(A) y = axial x y.
Eigen::Vector3d axialOfSkew(const Eigen::Matrix3d& A) {
  return 0.5 * Eigen::Vector3d(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1));
}

Eigen::Matrix3d gradientOf(const Tet10Vectors& x, const std::array<Eigen::Vector3d, 10>& g) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  for (size_t a = 0; a < 10; ++a)
    F.noalias() += x[a] * g[a].transpose();
  return F;
}

}  // namespace

QuadraticRestData quadraticRestData(const Eigen::Matrix3d& corner_rest_shape_inverse,
                                    double volume) {
  const Eigen::Matrix3d& B = corner_rest_shape_inverse;
  // grad L_1..3 are the rows of Bm; the barycentric coordinates sum to one.
  const std::array<Eigen::Vector3d, 4> gL = {-(B.row(0) + B.row(1) + B.row(2)).transpose(),
                                             B.row(0).transpose(), B.row(1).transpose(),
                                             B.row(2).transpose()};
  QuadraticRestData rest;
  rest.volume = volume;
  for (size_t q = 0; q < kTet10QuadraturePoints; ++q) {
    std::array<double, 4> L;
    for (size_t c = 0; c < 4; ++c)
      L[c] = c == q ? kA : kB;
    for (size_t a = 0; a < 4; ++a)
      rest.gradients[q][a] = (4 * L[a] - 1) * gL[a];
    for (size_t e = 0; e < 6; ++e) {
      const size_t i = static_cast<size_t>(kTet10Edges[e][0]);
      const size_t j = static_cast<size_t>(kTet10Edges[e][1]);
      rest.gradients[q][4 + e] = 4 * (L[i] * gL[j] + L[j] * gL[i]);
    }
  }
  rest.corner_gradients = gL;
  for (size_t e = 0; e < 6; ++e) {
    rest.centroid_edge_gradients[e] =
        gL[static_cast<size_t>(kTet10Edges[e][0])] + gL[static_cast<size_t>(kTet10Edges[e][1])];
  }
  return rest;
}

const Tet10GradientCoefficients& quadraticGradientCoefficients() {
  static const Tet10GradientCoefficients coefficients = [] {
    Tet10GradientCoefficients alpha{};  // zeros
    for (size_t q = 0; q < kTet10QuadraturePoints; ++q) {
      std::array<double, 4> L;
      for (size_t c = 0; c < 4; ++c)
        L[c] = c == q ? kA : kB;
      for (size_t a = 0; a < 4; ++a)
        alpha[q][a][a] = 4 * L[a] - 1;
      for (size_t e = 0; e < 6; ++e) {
        const size_t i = static_cast<size_t>(kTet10Edges[e][0]);
        const size_t j = static_cast<size_t>(kTet10Edges[e][1]);
        alpha[q][4 + e][j] = 4 * L[i];
        alpha[q][4 + e][i] = 4 * L[j];
      }
    }
    return alpha;
  }();
  return coefficients;
}

Eigen::Matrix3d quadraticDeformationGradient(const Tet10Vectors& x, const QuadraticRestData& rest,
                                             int q) {
  return gradientOf(x, rest.gradients[static_cast<size_t>(q)]);
}

Eigen::Matrix3d quadraticCentroidGradient(const Tet10Vectors& x, const QuadraticRestData& rest) {
  Eigen::Matrix3d F = Eigen::Matrix3d::Zero();
  for (size_t e = 0; e < 6; ++e)
    F.noalias() += x[4 + e] * rest.centroid_edge_gradients[e].transpose();
  return F;
}

QuadraticResponse quadraticResponse(const Tet10Vectors& x, const Eigen::Matrix3d& R,
                                    const QuadraticRestData& rest, double mu, double lambda) {
  QuadraticResponse response;
  for (Eigen::Vector3d& f : response.forces)
    f.setZero();
  const double weight = rest.volume / kTet10QuadraturePoints;
  Eigen::Vector3d torque = Eigen::Vector3d::Zero();  // dE / d omega, R -> R (I + [omega])
  for (size_t q = 0; q < kTet10QuadraturePoints; ++q) {
    const Eigen::Matrix3d RtF = R.transpose() * gradientOf(x, rest.gradients[q]);
    const Eigen::Matrix3d strain = 0.5 * (RtF + RtF.transpose()) - Eigen::Matrix3d::Identity();
    const double trace = strain.trace();
    const Eigen::Matrix3d stress = detail::linearStress(strain, mu, lambda);
    const Eigen::Matrix3d P = weight * (R * stress);
    for (size_t a = 0; a < 10; ++a)
      response.forces[a].noalias() -= P * rest.gradients[q][a];
    response.energy += weight * (mu * strain.squaredNorm() + 0.5 * lambda * trace * trace);
    torque += (2 * weight) * axialOfSkew(RtF * stress);
  }
  // The rotation's own response (see the header): R = polar(F_c) turns by
  // d omega = M^-1 sum_a (g_a x R^T dx_a), M = tr(S) I - S, S = sym(R^T F_c), so the exact
  // gradient adds f_a = R (g_a x M^-1 torque) on the mid-edge nodes (the corners' g_a is zero).
  // M's eigenvalues are the pairwise sums of S's (sign-fixed) singular values: positive unless
  // the element is inverted past a singular value's opposite. Where M is near singular, R is not a
  // smooth function of x and the fixed-R forces are kept until the element recovers.
  const Eigen::Matrix3d RtFc = R.transpose() * quadraticCentroidGradient(x, rest);
  const Eigen::Matrix3d S = 0.5 * (RtFc + RtFc.transpose());
  const Eigen::Matrix3d M = S.trace() * Eigen::Matrix3d::Identity() - S;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(M, Eigen::EigenvaluesOnly);
  if (eigen.eigenvalues()(0) > 1e-3 * std::abs(eigen.eigenvalues()(2))) {
    const Eigen::Vector3d zeta = M.ldlt().solve(torque);
    for (size_t e = 0; e < 6; ++e)
      response.forces[4 + e].noalias() += R * rest.centroid_edge_gradients[e].cross(zeta);
  }
  return response;
}

Tet10Vectors quadraticForceDifferential(const Tet10Vectors& dx, const Eigen::Matrix3d& R,
                                        const QuadraticRestData& rest, double mu, double lambda) {
  Tet10Vectors df;
  for (Eigen::Vector3d& f : df)
    f.setZero();
  const double weight = rest.volume / kTet10QuadraturePoints;
  for (size_t q = 0; q < kTet10QuadraturePoints; ++q) {
    const Eigen::Matrix3d RtdF = R.transpose() * gradientOf(dx, rest.gradients[q]);
    const Eigen::Matrix3d dP =
        weight * (R * detail::linearStress(0.5 * (RtdF + RtdF.transpose()), mu, lambda));
    for (size_t a = 0; a < 10; ++a)
      df[a].noalias() -= dP * rest.gradients[q][a];
  }
  return df;
}

Eigen::Matrix3d quadraticStiffnessBlock(const Eigen::Matrix3d& R, const QuadraticRestData& rest,
                                        double mu, double lambda, int a, int b) {
  const double weight = rest.volume / kTet10QuadraturePoints;
  Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
  for (size_t q = 0; q < kTet10QuadraturePoints; ++q) {
    const Eigen::Vector3d u = R * rest.gradients[q][static_cast<size_t>(a)];
    const Eigen::Vector3d w = R * rest.gradients[q][static_cast<size_t>(b)];
    block += weight * (mu * u.dot(w) * Eigen::Matrix3d::Identity() + mu * w * u.transpose() +
                       lambda * u * w.transpose());
  }
  return block;
}

}  // namespace torsion
