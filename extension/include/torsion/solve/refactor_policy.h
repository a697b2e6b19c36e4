#pragma once
// When a preconditioner that keeps a factorisation across steps refactorises it. The corotated
// stiffness changes with the element rotations, which turn little from one step to the next, so
// a factor of an earlier step's system stays a good preconditioner for a while; CG iterations
// growing is the sign that it no longer is. The decision depends on iteration counts alone, which
// are the same for any thread count (the products are), so lagged preconditioners stay
// deterministic.

#include "torsion/solve/solver_settings.h"

namespace torsion {

class RefactorPolicy {
 public:
  /// True when the coming solve must refactorise: no factor yet, refactor_interval solves done
  /// with this one, or the last solve took more than refactor_iterations CG iterations and more
  /// than the first solve with this factor did (a fresh factor that never reaches the threshold
  /// is not refactorised every step).
  bool due(const SolverSettings& settings) const {
    if (!has_factor_) return true;
    if (solves_ >= settings.refactor_interval) return true;
    return solves_ > 1 && last_iterations_ > settings.refactor_iterations &&
           last_iterations_ > first_iterations_;
  }
  void factorised() {
    has_factor_ = true;
    solves_ = 0;
    ++factorisations_;
  }
  /// After a failed factorisation, or when the system changed shape: refactorise next time.
  void invalidate() { has_factor_ = false; }
  /// Records a solve with the current factor.
  void solved(int iterations) {
    if (solves_ == 0) first_iterations_ = iterations;
    last_iterations_ = iterations;
    ++solves_;
  }
  /// Factorisations done so far (tests, benchmarks).
  long factorisations() const { return factorisations_; }

 private:
  bool has_factor_ = false;
  int solves_ = 0;
  int first_iterations_ = 0;
  int last_iterations_ = 0;
  long factorisations_ = 0;
};

}  // namespace torsion
