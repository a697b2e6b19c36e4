// Projected Gauss-Seidel on a frictional contact problem in contact space (coulomb_problem.h).

#include "torsion/contact/coulomb_problem.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

namespace torsion {

Eigen::Vector3d projectOntoCone(const Eigen::Vector3d& n, double mu, const Eigen::Vector3d& r) {
  const double rn = n.dot(r);
  const Eigen::Vector3d t = r - n * rn;
  const double s = t.norm();
  if (s <= mu * rn) return r;                         // inside
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

namespace {

// Everything the sweeps and the Newton iterations share.
struct Workspace {
  const CoulombProblem& problem;
  const Eigen::MatrixXd& W;
  // W plus a small compliance on its diagonal (CoulombSettings::newton_regularization of its
  // largest entry, 1e-6 by default), for the Newton steps' Jacobian only (F itself is always
  // W's): W is only semi-definite where contacts constrain the same motion (a face point and the
  // nodes of its triangle), and a box on a stiff slab makes it nearly so; the exact Jacobian's
  // steps then run along that null space (impulses moved between redundant contacts, 10 to 100
  // times the impulses themselves) and the line search stalls. Measured on a box landing on a stiff
  // slab (21 contacts): 1e-10 took 41 steps, 1e-6 24, 1e-4 did not converge in 50.
  Eigen::MatrixXd W_newton;
  int m;
  std::vector<double> normal_step, tangent_step;
  std::vector<Eigen::Matrix3d> bilateral_inverse;
  std::vector<Eigen::Matrix3d> frame;  // columns n, e1, e2

  bool bilateral(int i) const {
    return !problem.bilateral.empty() && problem.bilateral[static_cast<size_t>(i)] != 0;
  }
};

Workspace prepare(const CoulombProblem& problem, const CoulombSettings& settings) {
  Workspace ws{problem, problem.delassus, {}, problem.size(), {}, {}, {}, {}};
  ws.W_newton = ws.W;
  ws.W_newton.diagonal().array() += settings.newton_regularization * ws.W.diagonal().maxCoeff();
  const size_t m = static_cast<size_t>(ws.m);
  ws.normal_step.assign(m, 0.0);
  ws.tangent_step.assign(m, 0.0);
  ws.bilateral_inverse.resize(m);
  ws.frame.resize(m);
  for (int i = 0; i < ws.m; ++i) {
    const size_t si = static_cast<size_t>(i);
    const Eigen::Matrix3d block = ws.W.block<3, 3>(3 * i, 3 * i);
    const Eigen::Vector3d& n = problem.normal[si];
    const double wnn = n.dot(block * n);
    ws.normal_step[si] = wnn > 0 ? 1.0 / wnn : 0.0;
    ws.tangent_step[si] = tangentialStep(block, n);
    const Eigen::Vector3d e1 = n.unitOrthogonal();
    ws.frame[si] << n, e1, n.cross(e1);
    if (ws.bilateral(i)) {
      // A tiny regularisation keeps a rank-deficient block invertible; the sweeps remove what it
      // leaves.
      const double scale = std::max(block.trace(), 1e-300);
      ws.bilateral_inverse[si] = (block + 1e-12 * scale * Eigen::Matrix3d::Identity())
                                     .ldlt()
                                     .solve(Eigen::Matrix3d::Identity());
    }
  }
  return ws;
}

double worstResidual(const Workspace& ws, const Eigen::VectorXd& r, const Eigen::VectorXd& u) {
  double worst = 0;
  for (int i = 0; i < ws.m; ++i) {
    const size_t si = static_cast<size_t>(i);
    const Eigen::Vector3d ui = u.segment<3>(3 * i);
    if (ws.bilateral(i)) {
      worst = std::max(worst, ui.norm());
    } else if (ws.normal_step[si] > 0) {
      worst = std::max(worst, coulombResidual(ws.problem.normal[si], ws.problem.friction[si],
                                              r.segment<3>(3 * i), ui, ws.normal_step[si]));
    }
  }
  return worst;
}

// One projected Gauss-Seidel sweep over the contacts; u follows r.
void sweep(const Workspace& ws, Eigen::VectorXd& r, Eigen::VectorXd& u) {
  auto apply = [&](int i, const Eigen::Vector3d& delta) {
    r.segment<3>(3 * i) += delta;
    u.noalias() += ws.W.middleCols<3>(3 * i) * delta;
  };
  for (int i = 0; i < ws.m; ++i) {
    const size_t si = static_cast<size_t>(i);
    const Eigen::Vector3d& n = ws.problem.normal[si];
    if (ws.bilateral(i)) {
      apply(i, -(ws.bilateral_inverse[si] * u.segment<3>(3 * i)));
      continue;
    }
    if (ws.normal_step[si] == 0) continue;  // nothing moves this contact
    // Normal: the exact step along n, kept non-negative.
    const double rn = n.dot(r.segment<3>(3 * i));
    const double rn_new = std::max(0.0, rn - ws.normal_step[si] * n.dot(u.segment<3>(3 * i)));
    if (rn_new != rn) apply(i, n * (rn_new - rn));
    // Friction: a step against the slip, kept within the disc mu r_n.
    const Eigen::Vector3d ri = r.segment<3>(3 * i);
    const Eigen::Vector3d rt = ri - n * n.dot(ri);
    const Eigen::Vector3d ui = u.segment<3>(3 * i);
    Eigen::Vector3d rt_new = rt - ws.tangent_step[si] * (ui - n * n.dot(ui));
    rt_new -= n * n.dot(rt_new);
    const double bound = ws.problem.friction[si] * rn_new;
    const double size = rt_new.norm();
    if (size > bound) rt_new *= size > 0 ? bound / size : 0.0;
    if (rt_new != rt) apply(i, rt_new - rt);
  }
}

// Alart and Curnier's function F(r) (zero exactly at Coulomb's law) in each contact's frame
// (n, e1, e2), and, if `jacobian` is given, its generalised Jacobian dF/dr (world r).
//   normal   a = r_n - rho u_n;  F_n = rho u_n if a > 0 (in contact), else r_n
//   tangent  tau = r_t - rho u_t, R = mu max(a, 0);  F_t = rho u_t if |tau| <= R (stick),
//            else r_t - R tau / |tau| (slide: the friction on the disc, along tau)
// with rho = 1 / W_nn of the contact. A bilateral contact has F = rho u.
void alartCurnier(const Workspace& ws, const Eigen::VectorXd& r, const Eigen::VectorXd& u,
                  Eigen::VectorXd& F, Eigen::MatrixXd* jacobian) {
  const int m = ws.m;
  F.resize(3 * m);
  if (jacobian != nullptr) jacobian->setZero(3 * m, 3 * m);
  for (int i = 0; i < m; ++i) {
    const size_t si = static_cast<size_t>(i);
    const Eigen::Matrix3d& R = ws.frame[si];
    const double rho = ws.normal_step[si];
    const Eigen::Vector3d rl = R.transpose() * r.segment<3>(3 * i);
    const Eigen::Vector3d ul = R.transpose() * u.segment<3>(3 * i);
    // Rows of d(local u)/dr and d(local r)/dr.
    auto du = [&](int k) {
      return Eigen::RowVectorXd(R.col(k).transpose() * ws.W_newton.middleRows<3>(3 * i));
    };
    auto dr = [&](int k) {
      Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(3 * m);
      row.segment<3>(3 * i) = R.col(k).transpose();
      return row;
    };
    if (rho == 0) {  // no compliance: the contact cannot act
      F.segment<3>(3 * i) = rl;
      if (jacobian != nullptr)
        for (int k = 0; k < 3; ++k)
          jacobian->row(3 * i + k) = dr(k);
      continue;
    }
    if (ws.bilateral(i)) {
      F.segment<3>(3 * i) = rho * ul;
      if (jacobian != nullptr)
        for (int k = 0; k < 3; ++k)
          jacobian->row(3 * i + k) = rho * du(k);
      continue;
    }
    const double mu = ws.problem.friction[si];
    const double a = rl(0) - rho * ul(0);
    const bool touching = a > 0;
    F(3 * i) = touching ? rho * ul(0) : rl(0);
    if (jacobian != nullptr)
      jacobian->row(3 * i) = touching ? Eigen::RowVectorXd(rho * du(0)) : dr(0);
    const Eigen::Vector2d tau = rl.tail<2>() - rho * ul.tail<2>();
    const double radius = mu * std::max(a, 0.0);
    const double size = tau.norm();
    if (size <= radius) {
      F.segment<2>(3 * i + 1) = rho * ul.tail<2>();
      if (jacobian != nullptr) {
        jacobian->row(3 * i + 1) = rho * du(1);
        jacobian->row(3 * i + 2) = rho * du(2);
      }
      continue;
    }
    const Eigen::Vector2d direction = tau / size;
    F.segment<2>(3 * i + 1) = rl.tail<2>() - radius * direction;
    if (jacobian == nullptr) continue;
    Eigen::MatrixXd dtau(2, 3 * m);
    dtau.row(0) = dr(1) - rho * du(1);
    dtau.row(1) = dr(2) - rho * du(2);
    Eigen::RowVectorXd dradius = Eigen::RowVectorXd::Zero(3 * m);
    if (touching) dradius = mu * (dr(0) - rho * du(0));
    const Eigen::Matrix2d turn =
        (radius / size) * (Eigen::Matrix2d::Identity() - direction * direction.transpose());
    Eigen::MatrixXd rows(2, 3 * m);
    rows.row(0) = dr(1);
    rows.row(1) = dr(2);
    rows -= direction * dradius + turn * dtau;
    jacobian->middleRows<2>(3 * i + 1) = rows;
  }
}

// Generalised Newton on Alart and Curnier's function with a backtracking line search on |F|^2.
// Returns false when a step fails to decrease it (the caller sweeps instead).
bool newtonStep(const Workspace& ws, Eigen::VectorXd& r, Eigen::VectorXd& u) {
  Eigen::VectorXd F, F_trial, r_trial, u_trial;
  Eigen::MatrixXd J;
  alartCurnier(ws, r, u, F, &J);
  const double merit = F.squaredNorm();
  if (merit == 0) return true;
  const Eigen::VectorXd step = J.partialPivLu().solve(-F);
  if (!step.allFinite()) return false;
  for (double alpha = 1; alpha > 1e-4; alpha *= 0.5) {
    r_trial = r + alpha * step;
    u_trial = ws.problem.free_velocity + ws.W * r_trial;
    alartCurnier(ws, r_trial, u_trial, F_trial, nullptr);
    if (F_trial.squaredNorm() < (1 - 1e-4 * alpha) * merit) {
      r = r_trial;
      u = ws.problem.free_velocity + ws.W * r;
      return true;
    }
  }
  return false;
}

}  // namespace

CoulombReport solveCoulomb(const CoulombProblem& problem, const CoulombSettings& settings,
                           Eigen::VectorXd& r, Eigen::VectorXd& velocity) {
  const int m = problem.size();
  CoulombReport report;
  if (r.size() != 3 * m || !r.allFinite()) r.setZero(3 * m);
  velocity = problem.free_velocity + problem.delassus * r;
  if (m == 0) {
    report.converged = true;
    return report;
  }
  const Workspace ws = prepare(problem, settings);
  auto converged = [&]() {
    report.residual = worstResidual(ws, r, velocity);
    return report.residual <= settings.tolerance;
  };
  // A few sweeps find the states; Newton then converges fast whatever W's conditioning (a box
  // on a stiff slab: W is the box's rank-6 response plus a small compliance); sweeps take over
  // where a Newton step fails to make progress.
  // The best iterate is kept: the sweeps' residual is not monotone, and an unconverged solve
  // should end on its best answer, not its last.
  int newton_steps = 0;
  double best = std::numeric_limits<double>::infinity();
  Eigen::VectorXd best_r = r;
  while (report.sweeps < settings.max_sweeps && !converged()) {
    if (report.residual < best) {
      best = report.residual;
      best_r = r;
    }
    const bool try_newton = m <= settings.newton_max_contacts &&
                            report.sweeps >= settings.sweeps_before_newton &&
                            newton_steps < settings.max_newton_steps;
    if (try_newton) {
      ++newton_steps;
      ++report.newton_steps;
      if (newtonStep(ws, r, velocity)) continue;
    }
    sweep(ws, r, velocity);
    ++report.sweeps;
  }
  if (report.residual > best) {
    report.residual = best;
    r = best_r;
  }
  report.converged = report.residual <= std::max(settings.tolerance, settings.acceptable);
  // The velocities of the final impulses, free of the sweeps' accumulated rounding.
  velocity = problem.free_velocity + problem.delassus * r;
  return report;
}

}  // namespace torsion
