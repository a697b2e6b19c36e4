#pragma once
// The 6x6 local stiffness K_h of a grabbed patch (DESIGN.md section 4): how the wrench the body
// exerts on the patch after the next step changes when the patch's rigid pose changes by a small
// twist (translation m, rotation vector rad, about the point O) over that step, every other
// constrained node held. It is the condensed stiffness of the implicit step itself: for a unit
// twist e_k, the grabbed nodes get velocity J e_k / dt (J = [I, -[x - O]x]), the free ones
//   A_ff dv_f = -A_fg dv_g     (A the step's system matrix, projected CG)
// and the internal force changes by df = -(dt + beta) K dv, so column k is
//   [sum df ; sum (x - O) x df] + the lever-arm term sum [f]x [x - O]x e_rot.
// Six solves: refresh it every few steps, not every step. Simulation thread only.

#include <Eigen/Core>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/haptics/device_mapping.h"
#include "torsion/solve/projected_cg.h"

namespace torsion::haptics {

class PatchStiffness {
 public:
  /// dW/dpose of group `group` of `body` about `point`, with the body's current step system.
  /// `tolerance`: relative CG tolerance of the six solves (warm-started from the last call).
  Matrix6d compute(FemBody& body, int group, const Eigen::Vector3d& point, double tolerance);
  /// Total CG iterations of the last compute().
  int lastIterations() const { return iterations_; }

 private:
  ProjectedCg cg_;
  std::vector<Eigen::VectorXd> warm_;  // last solution per column
  Eigen::VectorXd zero_rhs_, stiffness_times_;
  int iterations_ = 0;
};

}  // namespace torsion::haptics
