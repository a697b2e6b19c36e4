#pragma once
// A FEM body in a SAP island (island_body.h): the step's SystemOperator, A = M (1 + dt alpha) +
// (dt^2 + dt beta) K with its coefficients already set, and the step's NodeConstraints, whose
// prescribed components (fixed, carried, or along one direction) are the prescribed dofs.
// b = M v0 + dt (f_elastic + f_external), as the implicit stepper builds it. The operator's
// diagonal blocks are read once, at construction: the body is valid for one step.

#include <Eigen/Core>
#include <vector>

#include "torsion/contact/solve/island_body.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/system_operator.h"

namespace torsion::sap {

class FemIslandBody final : public IslandBody {
 public:
  /// Neither `system` nor `constraints` is owned; both outlive the body.
  FemIslandBody(const SystemOperator& system, const NodeConstraints& constraints,
                Eigen::VectorXd momentum);

  int dofs() const override { return static_cast<int>(momentum_.size()); }
  int blockSize() const override { return 3; }
  void multiply(const Eigen::VectorXd& x, Eigen::VectorXd& out) const override;
  const Eigen::VectorXd& momentum() const override { return momentum_; }
  DiagonalBlock diagonalBlock(int node) const override;
  void filter(Eigen::VectorXd& x) const override { constraints_.filter(x); }
  void impose(Eigen::VectorXd& v) const override { constraints_.impose(v); }
  DiagonalBlock freeProjector(int node) const override;

 private:
  const SystemOperator& system_;
  const NodeConstraints& constraints_;
  Eigen::VectorXd momentum_;
  std::vector<Eigen::Matrix3d> blocks_;
};

}  // namespace torsion::sap
