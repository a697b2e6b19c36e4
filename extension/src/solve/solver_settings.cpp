#include "torsion/solve/solver_settings.h"

#include <cmath>

#include "torsion/format_number.h"

namespace torsion {

Status SolverSettings::validate() const {
  if (!(std::isfinite(time_step) && time_step >= kMinTimeStep && time_step <= 1))
    return Error{"solver: time_step = " + formatNumber(time_step) + ": must be in [" +
                 formatNumber(kMinTimeStep) + ", 1] s"};
  if (!(std::isfinite(tolerance) && tolerance > 0 && tolerance < 1))
    return Error{"solver: tolerance = " + formatNumber(tolerance) + ": must be in (0, 1)"};
  if (max_iterations < 1)
    return Error{"solver: max_iterations = " + std::to_string(max_iterations) + ": must be >= 1"};
  if (refactor_interval < 1)
    return Error{"solver: refactor_interval = " + std::to_string(refactor_interval) +
                 ": must be >= 1"};
  if (refactor_iterations < 0)
    return Error{"solver: refactor_iterations = " + std::to_string(refactor_iterations) +
                 ": must be >= 0"};
  if (threads < 0) return Error{"solver: threads = " + std::to_string(threads) + ": must be >= 0"};
  if (!(max_speed > 0)) return Error{"solver: max_speed must be > 0 m/s"};
  if (!(std::isfinite(newton_tolerance) && newton_tolerance > 0 && newton_tolerance < 1))
    return Error{"solver: newton_tolerance = " + formatNumber(newton_tolerance) +
                 ": must be in (0, 1)"};
  if (newton_max_iterations < 1)
    return Error{"solver: newton_max_iterations = " + std::to_string(newton_max_iterations) +
                 ": must be >= 1"};
  return Ok{};
}

const char* toString(LinearSolverKind kind) {
  switch (kind) {
    case LinearSolverKind::kConjugateGradient:
      return "cg";
    case LinearSolverKind::kCholmod:
      return "cholmod";
  }
  return "?";
}

const char* toString(PreconditionerKind kind) {
  switch (kind) {
    case PreconditionerKind::kJacobi:
      return "jacobi";
    case PreconditionerKind::kBlockJacobi:
      return "block_jacobi";
    case PreconditionerKind::kLaggedCholesky:
      return "lagged_cholesky";
    case PreconditionerKind::kIncompleteCholesky:
      return "incomplete_cholesky";
    case PreconditionerKind::kTwoLevel:
      return "two_level";
  }
  return "?";
}

}  // namespace torsion
