#pragma once
// The 6x6 local stiffness K_h of a grabbed patch (docs/design.md section 4): how the wrench the
// body exerts on the patch after the next step changes when the patch's rigid pose changes by a
// small twist (translation m, rotation vector rad, about the point O) over that step, every other
// constrained node held. It is the condensed stiffness of the implicit step itself: for a unit
// twist e_k, the grabbed nodes get velocity J e_k / dt (J = [I, -[x - O]x]), the free ones
//   A_ff dv_f = -A_fg dv_g     (A the step's system matrix, projected CG)
// and the internal force changes by df = -(dt + beta) K dv, so column k is
//   [sum df ; sum (x - O) x df] + the lever-arm term sum [f]x [x - O]x e_rot.
// Six solves: refresh it every few steps, not every step, and if need be a column per step
// (advance()), so that no single step is several times longer than the others. Simulation
// thread only.

#include <Eigen/Core>
#include <vector>

#include "torsion/haptics/device_mapping.h"
#include "torsion/solve/projected_cg.h"

namespace torsion {
class FemBody;  // torsion/bullet/fem_body.h
}  // namespace torsion

namespace torsion::haptics {

class PatchStiffness {
 public:
  /// dW/dpose of group `group` of `body` about `point`, with the body's current step system.
  /// `tolerance`: relative CG tolerance of the six solves (warm-started from the last call).
  Matrix6d compute(FemBody& body, int group, const Eigen::Vector3d& point, double tolerance);
  /// One part of a refresh: up to `columns` more columns (starting a refresh when none is under
  /// way), each with the body's system at the time. True when the sixth is done: matrix() is then
  /// the new K_h (its lever-arm term from the state at that time).
  bool advance(FemBody& body, int group, const Eigen::Vector3d& point, double tolerance,
               int columns);
  bool inProgress() const { return next_column_ > 0; }
  /// Abandons a refresh under way (the grabbed patch changed).
  void reset() { next_column_ = 0; }
  const Matrix6d& matrix() const { return matrix_; }

 private:
  Eigen::Matrix<double, 6, 1> column(FemBody& body, int group, const Eigen::Vector3d& point,
                                     double tolerance, int c);

  ProjectedCg cg_;
  std::vector<Eigen::VectorXd> warm_;  // last solution per column
  Eigen::VectorXd zero_rhs_, stiffness_times_;
  int next_column_ = 0;  // 0: no refresh under way
  Matrix6d partial_ = Matrix6d::Zero(), matrix_ = Matrix6d::Zero();
};

}  // namespace torsion::haptics
