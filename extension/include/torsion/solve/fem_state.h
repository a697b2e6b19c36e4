#pragma once
// The mutable state of one FEM body: what changes from step to step.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "torsion/fem/fem_model.h"

namespace torsion {

struct FemState {
  Eigen::VectorXd positions;   ///< 3n, m (node i at [3i, 3i+3))
  Eigen::VectorXd velocities;  ///< 3n, m/s
  /// Per-element rotation of the last step, warm start of the polar decomposition.
  std::vector<Eigen::Quaterniond> element_rotations;

  /// The body at rest in its mesh's rest shape.
  static FemState atRest(const FemModel& model);

  Eigen::Vector3d position(int node) const { return positions.segment<3>(3 * node); }
  Eigen::Vector3d velocity(int node) const { return velocities.segment<3>(3 * node); }
};

}  // namespace torsion
