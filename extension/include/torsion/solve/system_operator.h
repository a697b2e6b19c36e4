#pragma once
// The linearised backward-Euler system of one body at the current positions,
//   A = M (1 + dt alpha) + (dt^2 + dt beta) K,   K = Re Ke Re^T (rotations of this step),
// applied matrix-free. Owns the per-tet rotations of the step and a per-tet scratch buffer;
// products are gathered per node over the node's tets in a fixed order, so they are identical
// for any thread count.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "torsion/fem/fem_model.h"
#include "torsion/solve/parallel.h"

namespace torsion {

class SystemOperator {
 public:
  SystemOperator(std::shared_ptr<const FemModel> model, const Parallel& parallel);

  /// Sets the rotation of every tet for this step (from FemState::tet_rotations, refreshed
  /// by updateRotations) and the system coefficients.
  void setCoefficients(double mass_coefficient, double stiffness_coefficient);
  const std::vector<Eigen::Matrix3d>& rotations() const { return rotations_; }
  std::vector<Eigen::Matrix3d>& mutableRotations() { return rotations_; }

  /// out = A y.
  void multiply(const Eigen::VectorXd& y, Eigen::VectorXd& out) const;
  /// out = K y.
  void multiplyStiffness(const Eigen::VectorXd& y, Eigen::VectorXd& out) const;
  /// out_i = scale * sum of the per-tet values of node i (tet_values[t][a] belongs to node
  /// tets[t][a]), summed over the node's tets in ascending order.
  void gather(const std::vector<std::array<Eigen::Vector3d, 4>>& tet_values, double scale,
              Eigen::VectorXd& out) const;
  /// The 3x3 diagonal blocks of A, one per node.
  void diagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const;

  const FemModel& model() const { return *model_; }
  double massCoefficient() const { return mass_coefficient_; }
  double stiffnessCoefficient() const { return stiffness_coefficient_; }

 private:
  // out_i = mass_scale m_i y_i + stiffness_scale (K y)_i
  void apply(const Eigen::VectorXd& y, Eigen::VectorXd& out, double mass_scale,
             double stiffness_scale) const;

  std::shared_ptr<const FemModel> model_;
  const Parallel& parallel_;
  std::vector<Eigen::Matrix3d> rotations_;
  double mass_coefficient_ = 1;
  double stiffness_coefficient_ = 0;
  mutable std::vector<std::array<Eigen::Vector3d, 4>> tet_scratch_;
  std::vector<int> node_entries_;  // per node: 4 * tet + local index, node-major
  std::vector<int> node_offsets_;
};

}  // namespace torsion
