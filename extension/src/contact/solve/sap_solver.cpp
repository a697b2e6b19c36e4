// Newton's method with exact line search on the SAP cost (sap_solver.h).
#include "torsion/contact/solve/sap_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace torsion::sap {

namespace {

// The line search stops when |ell'(alpha)| is this small relative to |ell'(0)|, or relative to
// the size of the terms summed into it (below that, ell' is rounding).
constexpr double kSlopeTolerance = 1e-10;
constexpr double kSlopeRounding = 1e-13;
// A Newton step the line search cut below this fraction: the next direction takes the sliding
// rows' slip curvature (addSlipCurvature). Measured with `torsion run`, 1 thread, most Newton
// iterations in a step without -> with: soft_stack 86 -> 48, soft_grasp 80 -> 62, rigid_mix
// 42 -> 28, bullet_boxes 46 -> 32; a motor gripper holding a soft block (70 rows sliding at the
// warm start, sticking at the solution) 50 -> 18.5 a step; the plectoneme's slowly sliding coils
// 9 % fewer (docs/performance-contact.md). Only after a short step: from the start, on rows that
// go on sliding, the exact model converges faster (the plectoneme: 5.6 times the iterations).
constexpr double kShortStep = 0.5;

}  // namespace

double SapSolver::scaledNorm(const SapProblem& problem, const Eigen::VectorXd& x) const {
  return x.cwiseProduct(problem.inverseSqrtDiagonal()).norm();
}

SapReport SapSolver::solve(const SapProblem& problem, Eigen::VectorXd& v) {
  SapReport report;
  if (v.size() != problem.dofs()) v.setZero(problem.dofs());
  problem.impose(v);
  correction_ =
      problem.hasBodyPreconditioner() && problem.rowCount() <= settings_.max_correction_rows;
  if (correction_) prepareCorrection(problem);
  coupled_.forget();
  Eigen::VectorXd dv;
  double first_residual = 0;
  double alpha = 1;
  bool av_known = false;  // next_av_ = A v, carried from the last iterate (A dv from the CG)
  for (;;) {
    if (av_known) {
      problem.evaluate(v, std::move(next_av_), evaluation_);
    } else {
      problem.evaluate(v, evaluation_);
    }
    // The scales p = A v and j = J^T gamma, on the free dofs (the unknowns) only.
    z_ = evaluation_.av;
    problem.filter(z_);
    q_ = evaluation_.contact_impulse;
    problem.filter(q_);
    report.residual = scaledNorm(problem, evaluation_.gradient);
    report.tolerance =
        settings_.absolute_tolerance +
        settings_.relative_tolerance * std::max(scaledNorm(problem, z_), scaledNorm(problem, q_));
    if (report.residual <= report.tolerance) {
      report.converged = true;
      break;
    }
    if (!std::isfinite(report.residual)) {
      report.message = "non-finite residual";  // a non-finite b, A or warm start
      break;
    }
    if (report.newton_iterations >= settings_.max_newton_iterations) {
      report.message = "iteration cap";
      break;
    }
    if (report.newton_iterations == 0) first_residual = report.residual;
    // Inexact Newton: loose while far, tighter as the residual falls, never tighter than what
    // brings the residual to half the tolerance.
    double eta = std::min(settings_.max_forcing, std::sqrt(report.residual / first_residual));
    eta = std::max(eta, 0.5 * report.tolerance / report.residual);
    if (alpha < kShortStep) addSlipCurvature(problem);
    report.cg_iterations += newtonDirection(problem, eta, dv);
    alpha = lineSearch(problem, dv, report.line_search_iterations);
    const double step = alpha * dv.lpNorm<Eigen::Infinity>();
    if (!(step > std::numeric_limits<double>::epsilon() * v.lpNorm<Eigen::Infinity>())) {
      report.message = "no progress";  // the step no longer changes v: rounding
      break;
    }
    v += alpha * dv;
    // A (v + alpha dv) = A v + alpha A dv: a product saved per iteration (A v's rounding drifts
    // by a few ulps over a solve, far below its tolerance).
    next_av_ = evaluation_.av + alpha * a_dv_;
    av_known = true;
    ++report.newton_iterations;
  }
  fillReport(problem, report);
  return report;
}

void SapSolver::addSlipCurvature(const SapProblem& problem) {
  for (int i = 0; i < problem.rowCount(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    sap::addSlipCurvature(problem.model(i), evaluation_.contact_velocity[k], evaluation_.rows[k].g);
  }
}

void SapSolver::prepareCorrection(const SapProblem& problem) {
  // P0: the bodies' own preconditioners and the inverse of A's blocks (no contact terms).
  problem.preconditionerBlocks(preconditioner_);
  const int columns = 3 * problem.rowCount();
  correction_y_.resize(problem.dofs(), columns);
  for (int c = 0; c < columns; ++c) {
    residual_.setZero(problem.dofs());
    problem.addRowTranspose(c / 3, Eigen::Vector3d::Unit(c % 3), residual_);
    problem.applyPreconditioner(preconditioner_, residual_, z_);
    correction_y_.col(c) = z_;
  }
  correction_w_.resize(columns, columns);
  for (int c = 0; c < columns; ++c) {
    z_ = correction_y_.col(c);
    for (int i = 0; i < problem.rowCount(); ++i)
      correction_w_.block<3, 1>(3 * i, c) = problem.multiplyRow(i, z_);
  }
}

void SapSolver::preparePreconditioner(const SapProblem& problem) {
  if (!correction_) {
    coupled_.prepare(problem, evaluation_);
    return;
  }
  // I + G W, G = blockdiag(G_i) (zero for a separated row).
  capacitance_matrix_ = correction_w_;
  for (int i = 0; i < problem.rowCount(); ++i) {
    const Eigen::Matrix3d& g = evaluation_.rows[static_cast<size_t>(i)].g;
    capacitance_matrix_.middleRows<3>(3 * i) = g * correction_w_.middleRows<3>(3 * i);
  }
  capacitance_matrix_ += Eigen::MatrixXd::Identity(correction_w_.rows(), correction_w_.cols());
  capacitance_.compute(capacitance_matrix_);
}

void SapSolver::precondition(const SapProblem& problem, const Eigen::VectorXd& r,
                             Eigen::VectorXd& z) {
  if (!correction_) {
    coupled_.apply(problem, r, z);
    return;
  }
  problem.applyPreconditioner(preconditioner_, r, z);
  if (problem.rowCount() == 0) return;
  // z = P0 r - Y (I + G W)^-1 G J P0 r.
  row_values_.resize(3 * problem.rowCount());
  for (int i = 0; i < problem.rowCount(); ++i)
    row_values_.segment<3>(3 * i) =
        evaluation_.rows[static_cast<size_t>(i)].g * problem.multiplyRow(i, z);
  z.noalias() -= correction_y_ * capacitance_.solve(row_values_);
}

int SapSolver::newtonDirection(const SapProblem& problem, double eta, Eigen::VectorXd& dv) {
  const Eigen::VectorXd& g = evaluation_.gradient;
  preparePreconditioner(problem);
  dv.setZero(problem.dofs());
  a_dv_.setZero(problem.dofs());
  residual_ = -g;
  precondition(problem, residual_, z_);
  p_ = z_;
  double rz = residual_.dot(z_);
  const double target = eta * scaledNorm(problem, residual_);
  int iterations = 0;
  while (iterations < settings_.max_cg_iterations && scaledNorm(problem, residual_) > target) {
    problem.multiplyHessian(evaluation_, p_, ap_, q_);
    const double curvature = p_.dot(q_);
    if (!(curvature > 0)) break;  // rounding: nothing left to gain along p
    const double a = rz / curvature;
    dv += a * p_;
    a_dv_ += a * ap_;
    residual_ -= a * q_;
    precondition(problem, residual_, z_);
    const double rz_next = residual_.dot(z_);
    p_ = z_ + (rz_next / rz) * p_;
    rz = rz_next;
    ++iterations;
  }
  // CG from zero descends after any number of iterations; this guards against rounding only.
  if (!(g.dot(dv) < 0)) {
    precondition(problem, g, dv);
    dv = -dv;
    problem.multiplyA(dv, a_dv_);
  }
  return iterations;
}

double SapSolver::lineSearch(const SapProblem& problem, const Eigen::VectorXd& dv,
                             int& iterations) {
  const SapEvaluation& e = evaluation_;  // a_dv_ = A dv, from newtonDirection
  line_linear_ = dv.dot(e.av) - dv.dot(problem.momentum());
  line_quadratic_ = dv.dot(a_dv_);
  line_vc_ = e.contact_velocity;
  line_dvc_.resize(line_vc_.size());
  for (int i = 0; i < problem.rowCount(); ++i)
    line_dvc_[static_cast<size_t>(i)] = problem.multiplyRow(i, dv);
  double slope0 = 0, curvature = 0, noise = 0;
  slopeAt(problem, 0, slope0, curvature, noise);
  if (!(slope0 < 0)) return 0;
  // ell' is monotone (ell convex): [lo, hi] brackets its root, lo where ell' < 0.
  double lo = 0, hi = std::numeric_limits<double>::infinity(), alpha = 1;
  for (int k = 0; k < settings_.max_line_search_iterations; ++k) {
    ++iterations;
    double slope = 0;
    slopeAt(problem, alpha, slope, curvature, noise);
    if (std::abs(slope) <= std::max(-kSlopeTolerance * slope0, kSlopeRounding * noise))
      return alpha;
    if (slope < 0) {
      lo = alpha;
    } else {
      hi = alpha;
    }
    if (hi - lo <= 4 * std::numeric_limits<double>::epsilon() * hi) break;
    // Newton on ell'; bisection when it leaves the bracket (a kink of ell'' in between).
    double next = alpha - slope / curvature;
    if (!(next > lo && next < hi)) next = std::isfinite(hi) ? 0.5 * (lo + hi) : 2 * alpha;
    alpha = next;
  }
  // Out of iterations or bracket: lo is on the descending side, so ell(lo) < ell(0).
  return lo > 0 ? lo : alpha;
}

void SapSolver::slopeAt(const SapProblem& problem, double alpha, double& slope, double& curvature,
                        double& noise) const {
  // ell(v + alpha dv) = ell_A(alpha) + sum_i ell_i(v_c,i + alpha J_i dv), with
  // ell_A' = dv.(A v - b) + alpha dv.A dv and ell_i' = -(J_i dv).gamma_i.
  slope = line_linear_ + alpha * line_quadratic_;
  curvature = line_quadratic_;
  noise = std::abs(line_linear_) + alpha * std::abs(line_quadratic_);
  for (int i = 0; i < problem.rowCount(); ++i) {
    const auto k = static_cast<size_t>(i);
    const RowResponse r = projectImpulse(problem.model(i), line_vc_[k] + alpha * line_dvc_[k]);
    const double contact = line_dvc_[k].dot(r.gamma);
    slope -= contact;
    noise += std::abs(contact);
    curvature += line_dvc_[k].dot(r.g * line_dvc_[k]);
  }
}

void SapSolver::fillReport(const SapProblem& problem, SapReport& report) const {
  const auto rows = static_cast<size_t>(problem.rowCount());
  report.cost = evaluation_.cost;
  report.impulses.resize(rows);
  report.states.resize(rows);
  report.contact_velocities = evaluation_.contact_velocity;
  for (size_t i = 0; i < rows; ++i) {
    report.impulses[i] = evaluation_.rows[i].gamma;
    report.states[i] = evaluation_.rows[i].state;
  }
}

}  // namespace torsion::sap
