// Projected Gauss-Seidel on a frictional contact problem in contact space (coulomb_problem.h).

#include "torsion/contact/coulomb_problem.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace torsion {

Eigen::Vector3d projectOntoCone(const Eigen::Vector3d& n, double mu, const Eigen::Vector3d& r) {
  const double rn = n.dot(r);
  const Eigen::Vector3d t = r - n * rn;
  const double s = t.norm();
  if (s <= mu * rn) return r;                       // inside
  if (mu * s <= -rn) return Eigen::Vector3d::Zero();  // in the polar cone
  const double rn_new = (rn + mu * s) / (1 + mu * mu);
  Eigen::Vector3d out = n * rn_new;
  if (s > 0) out += t * (mu * rn_new / s);
  return out;
}

double coulombResidual(const Eigen::Vector3d& n, double mu, const Eigen::Vector3d& r,
                       const Eigen::Vector3d& u, double step) {
  const double un = n.dot(u);
  const Eigen::Vector3d ut = u - n * un;
  const Eigen::Vector3d modified = u + n * (mu * ut.norm());
  return (r - projectOntoCone(n, mu, r - step * modified)).norm() / step;
}

namespace {

// The tangential step of contact i: the inverse of the largest eigenvalue of W_ii on the tangent
// plane (a step that never overshoots the stick of the contact alone).
double tangentialStep(const Eigen::Matrix3d& block, const Eigen::Vector3d& n) {
  const Eigen::Vector3d e1 = n.unitOrthogonal();
  const Eigen::Vector3d e2 = n.cross(e1);
  const double a = e1.dot(block * e1);
  const double b = e1.dot(block * e2);
  const double c = e2.dot(block * e2);
  const double largest = 0.5 * (a + c) + std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  return largest > 0 ? 1.0 / largest : 0.0;
}

}  // namespace

CoulombReport solveCoulomb(const CoulombProblem& problem, const CoulombSettings& settings,
                           Eigen::VectorXd& r, Eigen::VectorXd& velocity) {
  const int m = problem.size();
  const Eigen::MatrixXd& W = problem.delassus;
  CoulombReport report;
  if (r.size() != 3 * m) r.setZero(3 * m);
  velocity = problem.free_velocity + W * r;
  if (m == 0) {
    report.converged = true;
    return report;
  }

  std::vector<double> normal_step(static_cast<size_t>(m), 0.0);
  std::vector<double> tangent_step(static_cast<size_t>(m), 0.0);
  std::vector<Eigen::Matrix3d> bilateral_inverse(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) {
    const size_t si = static_cast<size_t>(i);
    const Eigen::Matrix3d block = W.block<3, 3>(3 * i, 3 * i);
    const Eigen::Vector3d& n = problem.normal[si];
    const double wnn = n.dot(block * n);
    normal_step[si] = wnn > 0 ? 1.0 / wnn : 0.0;
    tangent_step[si] = tangentialStep(block, n);
    if (!problem.bilateral.empty() && problem.bilateral[si] != 0) {
      // A tiny regularisation keeps a rank-deficient block invertible; the sweeps remove what it
      // leaves.
      const double scale = std::max(block.trace(), 1e-300);
      bilateral_inverse[si] =
          (block + 1e-12 * scale * Eigen::Matrix3d::Identity()).ldlt().solve(
              Eigen::Matrix3d::Identity());
    }
  }

  auto apply = [&](int i, const Eigen::Vector3d& delta) {
    r.segment<3>(3 * i) += delta;
    velocity.noalias() += W.middleCols<3>(3 * i) * delta;
  };

  for (int sweep = 0; sweep < settings.max_sweeps; ++sweep) {
    for (int i = 0; i < m; ++i) {
      const size_t si = static_cast<size_t>(i);
      const Eigen::Vector3d& n = problem.normal[si];
      if (!problem.bilateral.empty() && problem.bilateral[si] != 0) {
        apply(i, -(bilateral_inverse[si] * velocity.segment<3>(3 * i)));
        continue;
      }
      if (normal_step[si] == 0) continue;  // nothing moves this contact
      // Normal: the exact step along n, kept non-negative.
      const double rn = n.dot(r.segment<3>(3 * i));
      const double rn_new = std::max(0.0, rn - normal_step[si] * n.dot(velocity.segment<3>(3 * i)));
      if (rn_new != rn) apply(i, n * (rn_new - rn));
      // Friction: a step against the slip, kept within the disc mu r_n.
      const Eigen::Vector3d ri = r.segment<3>(3 * i);
      const Eigen::Vector3d rt = ri - n * n.dot(ri);
      const Eigen::Vector3d ui = velocity.segment<3>(3 * i);
      Eigen::Vector3d rt_new = rt - tangent_step[si] * (ui - n * n.dot(ui));
      rt_new -= n * n.dot(rt_new);
      const double bound = problem.friction[si] * rn_new;
      const double size = rt_new.norm();
      if (size > bound) rt_new *= size > 0 ? bound / size : 0.0;
      if (rt_new != rt) apply(i, rt_new - rt);
    }
    ++report.sweeps;
    double worst = 0;
    for (int i = 0; i < m; ++i) {
      const size_t si = static_cast<size_t>(i);
      const Eigen::Vector3d ui = velocity.segment<3>(3 * i);
      if (!problem.bilateral.empty() && problem.bilateral[si] != 0) {
        worst = std::max(worst, ui.norm());
      } else if (normal_step[si] > 0) {
        worst = std::max(worst, coulombResidual(problem.normal[si], problem.friction[si],
                                                r.segment<3>(3 * i), ui, normal_step[si]));
      }
    }
    report.residual = worst;
    if (worst <= settings.tolerance) {
      report.converged = true;
      break;
    }
  }
  // The velocities of the final impulses, free of the sweeps' accumulated rounding.
  velocity = problem.free_velocity + W * r;
  return report;
}

}  // namespace torsion
