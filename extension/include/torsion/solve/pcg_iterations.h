#pragma once
// The preconditioned conjugate-gradient iterations shared by every CG in the project: the
// projected CG of the implicit step (projected_cg.h) and the contact solve, which adds rigid-body
// velocities to the unknowns (contact/rigid_contact.h). Each caller brings its own operator and
// preconditioner (both already restricted to its free subspace), the initial residual and the
// reference its tolerance is relative to; the loop is the same.

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "torsion/solve/projected_cg.h"

namespace torsion {

/// Iterates x += alpha p until |r| <= tolerance * reference or max_iterations.
///   apply(in, out):        out = A in (restricted to the free subspace)
///   precondition(in, out): out = M^-1 in (restricted likewise)
/// `r` holds the residual b - A x of the starting x on entry and is updated in place.
/// Reports breakdown on non-positive curvature or a non-finite residual.
template <class Apply, class Precondition>
LinearSolveReport pcgIterations(const Apply& apply, const Precondition& precondition,
                                double reference, const SolverSettings& settings,
                                Eigen::VectorXd& x, Eigen::VectorXd& r, PcgScratch& s) {
  LinearSolveReport report;
  double residual = r.norm();
  // Before the convergence test: inf <= tolerance * inf would pass an overflowed system as
  // solved in 0 iterations. A norm overflows once entries pass ~1e154: the arithmetic cannot
  // carry such a system either.
  if (!std::isfinite(reference) || !std::isfinite(residual)) {
    report.relative_residual = std::numeric_limits<double>::infinity();
    return brokenDown(report, "the right-hand side or the matrix is not finite (overflow)");
  }
  if (reference == 0.0 || residual <= settings.tolerance * reference) {
    report.relative_residual = reference > 0 ? residual / reference : 0.0;
    report.converged = true;
    return report;
  }
  precondition(r, s.z);
  s.p = s.z;
  double rz = r.dot(s.z);
  for (int k = 0; k < settings.max_iterations; ++k) {
    apply(s.p, s.q);
    const double pq = s.p.dot(s.q);
    if (!(pq > 0)) {  // A is SPD on the free subspace: anything else means a broken system
      report.breakdown = true;
      break;
    }
    const double alpha = rz / pq;
    x += alpha * s.p;
    r -= alpha * s.q;
    report.iterations = k + 1;
    residual = r.norm();
    if (residual <= settings.tolerance * reference) {
      report.converged = true;
      break;
    }
    precondition(r, s.z);
    const double rz_next = r.dot(s.z);
    s.p = s.z + (rz_next / rz) * s.p;
    rz = rz_next;
  }
  report.relative_residual = residual / reference;
  if (!std::isfinite(report.relative_residual) || !x.allFinite())
    return brokenDown(report, "the residual or the solution became non-finite");
  return report;
}

}  // namespace torsion
