#pragma once
// Settings of the implicit step, with defaults, units and validation.

#include <string>

#include "torsion/result.h"

namespace torsion {

enum class LinearSolverKind {
  kConjugateGradient,  ///< matrix-free preconditioned CG, warm-started from the last velocity
  kCholmod,            ///< sparse direct Cholesky, assembled every step: SuiteSparse CHOLMOD, or
                       ///< Eigen's SimplicialLLT in a build with TORSION_CHOLMOD=OFF
};

enum class PreconditionerKind {
  kJacobi,       ///< inverse diagonal of the system matrix
  kBlockJacobi,  ///< inverse 3x3 node blocks: captures each node's anisotropic stiffness
  /// CHOLMOD factor of the whole system, kept across steps and refactorised by the policy of
  /// SolverSettings::refactor_interval / refactor_iterations (the corotated K changes slowly).
  kLaggedCholesky,
  /// Eigen's IncompleteCholesky (limited fill, AMD order) of the system, lagged the same way.
  kIncompleteCholesky,
  /// tet10: a two-level (p-multigrid) cycle, block-Jacobi smoothing on all nodes and the Galerkin
  /// system on the corner nodes (the tet4 problem) solved by a lagged CHOLMOD factor. On tet4 the
  /// corner nodes are all nodes: the same as kLaggedCholesky.
  kTwoLevel,
};

/// s: the shortest step accepted. Bullet skips a step at or below its epsilon (1.2e-7 s with float
/// Bullet, 2.2e-16 s with double) without stepping anything, so a FemWorld set to such a dt would
/// report steps in which nothing moved; 1 us is also far below any step a twist, a contact or the
/// 1 kHz haptic loop needs.
inline constexpr double kMinTimeStep = 1e-6;

struct SolverSettings {
  double time_step = 0.01;  ///< dt, s, in [kMinTimeStep, 1]
  LinearSolverKind linear_solver = LinearSolverKind::kConjugateGradient;
  PreconditionerKind preconditioner = PreconditionerKind::kBlockJacobi;
  /// CG stops when |S(b - A v)| <= tolerance |S(b - A v_prescribed)|, the residual of the
  /// constrained system relative to its right-hand side.
  double tolerance = 1e-4;
  int max_iterations = 300;  ///< CG iteration cap
  /// Lagged preconditioners (kLaggedCholesky, kIncompleteCholesky, kTwoLevel's coarse level) are
  /// refactorised at the first solve, after this many solves with the same factor, and after a
  /// solve that took more than refactor_iterations CG iterations.
  int refactor_interval = 100;
  int refactor_iterations = 8;
  int threads = 0;  ///< worker threads; 0: TORSION_THREADS when set, else all cores
  /// A node faster than this (m/s) means the simulation blew up; the run stops.
  double max_speed = 1e3;
  /// Hyperelastic bodies (Material::law): the step's Newton solve stops when the free part of
  /// its residual (the momentum balance of backward Euler, N s) falls to newton_tolerance times
  /// its scale: |S(b - A v_prescribed)| of the step's first linear system (the reference the CG
  /// tolerance uses) plus dt |f(x_n)| (the elastic forces at the step's start, reactions
  /// included). Stopping at the cap within 10x is a warning; above, the step failed.
  double newton_tolerance = 1e-6;
  int newton_max_iterations = 30;  ///< Newton iterations (linear solves) per step, cap

  Status validate() const;
};

const char* toString(LinearSolverKind kind);
const char* toString(PreconditionerKind kind);

}  // namespace torsion
