#pragma once
// A FEM body in a SAP island (island_body.h): the step's SystemOperator, A = M (1 + dt alpha) +
// (dt^2 + dt beta) K with its coefficients already set, and the step's NodeConstraints, whose
// prescribed components (fixed, carried, or along one direction) are the prescribed dofs.
// b = M v0 + dt (f_elastic + f_external), as the implicit stepper builds it. The operator's
// diagonal blocks are read at construction and at beginStep(): the body is valid for the step it
// last read (a FemBody keeps one from step to step, FemBody::islandBody, for its storage).
//
// Its preconditioner in the island's CG (island_body.h), by default none (the island's
// block-Jacobi with the contact blocks). usePreconditioner() hands it the step's CHOLMOD factor
// (CholmodSolver::factorize at this step's operator and constraints): P0 = A^-1 on the free dofs,
// exactly, to which the solver adds the contacts by the capacitance correction (sap_solver.h).
// Not owned: it must hold this step's factor for as long as the body is solved with. (The body's
// incomplete Cholesky factor was measured in that place and lost to block-Jacobi everywhere:
// docs/contact-sap.md, "Cost".)
//
// useCoarseSpace() gives it the rigid modes of its aggregates (coarse_space.h) for the island's
// block-Jacobi CG.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "torsion/contact/solve/coarse_space.h"
#include "torsion/contact/solve/island_body.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/system_operator.h"

namespace torsion::sap {

class FemIslandBody final : public IslandBody {
 public:
  /// Neither `system` nor `constraints` is owned; both outlive the body.
  FemIslandBody(const SystemOperator& system, const NodeConstraints& constraints,
                Eigen::VectorXd momentum);
  /// The same body at a new step: b (3n) and the operator's diagonal blocks read again. The coarse
  /// space and the preconditioner are dropped until useCoarseSpace() or usePreconditioner().
  void beginStep(const Eigen::VectorXd& momentum);

  int dofs() const override { return static_cast<int>(momentum_.size()); }
  int blockSize() const override { return 3; }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const override;
  const Eigen::VectorXd& momentum() const override { return momentum_; }
  DiagonalBlock diagonalBlock(int node) const override;
  void filter(Eigen::VectorXd& x) const override { constraints_.filter(x); }
  void impose(Eigen::VectorXd& v) const override { constraints_.impose(v); }
  DiagonalBlock freeProjector(int node) const override;

  /// Preconditions with the step's factor (factor.factorized() must hold).
  void usePreconditioner(const CholmodSolver& factor);
  bool hasPreconditioner() const override { return factor_ != nullptr; }
  void applyPreconditioner(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;

  /// Builds the body's coarse space at `positions` (3n, the step's current node positions) with
  /// `aggregates` aggregates of the mesh's rest shape (0: aggregateCountFor its rest shape, which
  /// gives a body less slender than kMinSlenderness none). The aggregates of the last call are
  /// kept for the next with the same count.
  void useCoarseSpace(const Eigen::VectorXd& positions, int aggregates = 0);
  const NodeCoarseSpace* coarseSpace() const override {
    return coarse_current_ ? coarse_.get() : nullptr;
  }

 private:
  const SystemOperator& system_;
  const NodeConstraints& constraints_;
  Eigen::VectorXd momentum_;
  std::vector<Eigen::Matrix3d> blocks_;
  const CholmodSolver* factor_ = nullptr;
  std::unique_ptr<NodeCoarseSpace> coarse_;
  bool coarse_current_ = false;  // coarse_ is of this step
};

}  // namespace torsion::sap
