#pragma once
// The corotated tet4 force kernel's inputs for one pass over a body's tets: shared by the
// corotated force pass (implicit_stepper.cpp) and the rotation pass that gives a hyperelastic
// body's K_0 its rotations (implicit_stepper_newton.cpp), so that both read the same rest data,
// warm-start from the same quaternions and write the rotated gradients K's assembly reads.

#include <Eigen/Core>
#include <vector>

#include "system_operator_kernels.h"
#include "torsion/fem/fem_model.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

// The kernel's input for `model`'s tets at `state` with Lame constants mu, lambda: it writes
// `outputs` (rotations and rotated gradients) and flags in `needs_svd` (sized here) the tets it
// leaves to the SVD path. Without `forces` set (the caller's, with `energy`) it computes the
// rotations only.
inline system_kernels::Tet4ForceInput tet4ForceInput(const FemModel& model, FemState& state,
                                                     double mu, double lambda,
                                                     const SystemOperator::RotationOutputs& outputs,
                                                     std::vector<unsigned char>& needs_svd) {
  static_assert(sizeof(TetRestData) == 10 * sizeof(double), "Bm then V, no padding");
  needs_svd.resize(static_cast<size_t>(model.elementCount()));
  system_kernels::Tet4ForceInput in;
  in.positions = state.positions.data();
  in.nodes = model.elementNodes().data();
  in.rest = model.tetRestData().data()->rest_shape_inverse.data();
  in.mu = mu;
  in.lambda = lambda;
  in.quaternions = state.element_rotations.data()->coeffs().data();
  in.rotations = outputs.rotations.data()->data();
  in.rotated_gradients = outputs.rotated_gradients.data()->data();
  in.needs_svd = needs_svd.data();
  return in;
}

}  // namespace torsion
