#include "torsion/analysis/deformation_metrics.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>

namespace torsion {

double elementStrain(const Eigen::Matrix3d& deformation_gradient) {
  // Singular values are the square roots of the eigenvalues of F^T F (closed form for 3x3).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(deformation_gradient.transpose() * deformation_gradient,
                      Eigen::EigenvaluesOnly);
  Eigen::Vector3d s = eigen.eigenvalues().cwiseMax(0).cwiseSqrt();  // ascending
  if (deformation_gradient.determinant() < 0) s(0) = -s(0);         // the least-stretched axis
  return (s.array() - 1).abs().maxCoeff();
}

namespace {

Eigen::Matrix3d tetDeformationGradient(const FemModel& model, const Eigen::VectorXd& positions,
                                       size_t t) {
  const auto& tet = model.mesh().tets()[t];
  const Eigen::Vector3d x0 = positions.segment<3>(3 * tet[0]);
  Eigen::Matrix3d ds;
  for (int k = 0; k < 3; ++k)
    ds.col(k) = positions.segment<3>(3 * tet[static_cast<size_t>(k + 1)]) - x0;
  return ds * model.tetRestData()[t].rest_shape_inverse;
}

}  // namespace

int countInvertedTets(const FemModel& model, const Eigen::VectorXd& positions) {
  return InvertedTetCounter(model).count(model, positions);
}

// Rounding (u = 2^-53, no FMA contraction in this library's builds). With Ds the edge matrix
// (columns x1 - x0, x2 - x0, x3 - x0, the same rounded differences in both computations) and R
// the product of the row sums of |Ds| (R >= permanent(|Ds|)):
//  - the triple product d below differs from det Ds by at most 5.01 u R (two products, a
//    difference, a product and two sums per term);
//  - countInvertedTets()'s det(fl(Ds Bm)) differs from det(Ds) det(Bm) by at most
//    14.1 u R |Bm|_inf^3 (3 u per entry of the product, 5 u in the 3x3 determinant).
// So where |d| > (8 + 32 K) u R, K = max over tets of |Bm|_inf^3 / det Bm, det Ds and det F both
// have the sign of d, and d alone decides.
InvertedTetCounter::InvertedTetCounter(const FemModel& model) {
  constexpr double u = 0.5 * std::numeric_limits<double>::epsilon();
  double worst = 0;  // K
  for (const TetRestData& rest : model.tetRestData()) {
    const Eigen::Matrix3d& bm = rest.rest_shape_inverse;
    const double norm = bm.cwiseAbs().rowwise().sum().maxCoeff();
    const double cube = norm * norm * norm;
    const double det = bm.determinant();
    const double error = 8 * u * cube;  // of det, generously
    if (!(det > 1e3 * error) || !std::isfinite(cube)) {
      worst = std::numeric_limits<double>::infinity();  // no bound: every tet by det F
      break;
    }
    worst = std::max(worst, cube / (det - error));
  }
  threshold_ = (8 + 32 * worst) * u;
}

int InvertedTetCounter::count(const FemModel& model, const Eigen::VectorXd& positions) const {
  const std::vector<Tet>& tets = model.mesh().tets();
  const double* x = positions.data();
  const double threshold = threshold_;
  // Every edge component is at most the body's extent along its axis, so R <= 27 x y z extents:
  // one bound for all tets (tets far from flat pass it), the tet's own R for the rest. Non-finite
  // positions make it NaN and every tet goes by det F.
  const int nodes = static_cast<int>(positions.size() / 3);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  bool finite = true;
  for (int i = 0; i < nodes; ++i) {
    const Eigen::Map<const Eigen::Vector3d> p(x + 3 * i);
    finite = finite && p.allFinite();
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const Eigen::Vector3d extent = hi - lo;
  const double body_rows = finite ? 27 * extent.x() * extent.y() * extent.z() : 0.0;
  const double body_bound = threshold * body_rows;
  const bool body_bound_usable = body_rows >= 1e-200 && std::isfinite(body_bound);
  const size_t count = tets.size();
  int inverted = 0;
  for (size_t t = 0; t < count; ++t) {
    const Tet& tet = tets[t];
    const double* p0 = x + 3 * tet[0];
    const double* p1 = x + 3 * tet[1];
    const double* p2 = x + 3 * tet[2];
    const double* p3 = x + 3 * tet[3];
    // Ds = [e1 e2 e3], as tetDeformationGradient() forms it.
    const double ax = p1[0] - p0[0], ay = p1[1] - p0[1], az = p1[2] - p0[2];
    const double bx = p2[0] - p0[0], by = p2[1] - p0[1], bz = p2[2] - p0[2];
    const double cx = p3[0] - p0[0], cy = p3[1] - p0[1], cz = p3[2] - p0[2];
    const double d = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx);
    if (body_bound_usable && std::abs(d) > body_bound) {
      inverted += d < 0;
      continue;
    }
    const double rows = (std::abs(ax) + std::abs(bx) + std::abs(cx)) *
                        (std::abs(ay) + std::abs(by) + std::abs(cy)) *
                        (std::abs(az) + std::abs(bz) + std::abs(cz));
    // rows >= 1e-200: the products stay clear of subnormals, where the bound above fails.
    if (rows >= 1e-200 && std::abs(d) > threshold * rows) {
      inverted += d < 0;
    } else if (!(tetDeformationGradient(model, positions, t).determinant() > 0)) {
      ++inverted;
    }
  }
  return inverted;
}

DeformationMetrics measureDeformation(const FemModel& model, const Eigen::VectorXd& positions) {
  DeformationMetrics metrics;
  for (size_t t = 0; t < model.mesh().tets().size(); ++t) {
    const Eigen::Matrix3d f = tetDeformationGradient(model, positions, t);
    if (!(f.determinant() > 0)) ++metrics.inverted_tets;
    const double strain = elementStrain(f);
    if (!(strain <= metrics.max_strain)) {  // also takes NaN, so it is never hidden
      metrics.max_strain = strain;
      metrics.max_strain_tet = static_cast<int>(t);
    }
  }
  return metrics;
}

}  // namespace torsion
