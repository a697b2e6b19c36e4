#include "torsion/solve/fem_state.h"

namespace torsion {

FemState FemState::atRest(const FemModel& model) {
  FemState s;
  const int n = model.nodeCount();
  s.positions.resize(3 * n);
  for (int i = 0; i < n; ++i)
    s.positions.segment<3>(3 * i) = model.mesh().restPositions()[static_cast<size_t>(i)];
  s.velocities.setZero(3 * n);
  s.element_rotations.assign(static_cast<size_t>(model.elementCount()),
                             Eigen::Quaterniond::Identity());
  return s;
}

}  // namespace torsion
