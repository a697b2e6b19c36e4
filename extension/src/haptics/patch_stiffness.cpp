#include "torsion/haptics/patch_stiffness.h"

#include <Eigen/Geometry>

#include "torsion/bullet/fem_body.h"

namespace torsion::haptics {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Matrix6d PatchStiffness::compute(FemBody& body, int group, const Eigen::Vector3d& point,
                                 double tolerance) {
  reset();
  advance(body, group, point, tolerance, 6);
  return matrix_;
}

bool PatchStiffness::advance(FemBody& body, int group, const Eigen::Vector3d& point,
                             double tolerance, int columns) {
  if (next_column_ == 0) partial_.setZero();
  for (int k = 0; k < columns && next_column_ < 6; ++k, ++next_column_)
    partial_.col(next_column_) = column(body, group, point, tolerance, next_column_);
  if (next_column_ < 6) return false;
  next_column_ = 0;
  // The lever arms turn with the patch: d(r x f) = (dtheta x r) x f = [f]x [r]x dtheta.
  const Eigen::VectorXd& x = body.state().positions;
  const Eigen::VectorXd& forces = body.stepper().internalForces();
  for (int node : body.groups()[static_cast<size_t>(group)]->nodes()) {
    const Eigen::Vector3d r = x.segment<3>(3 * node) - point;
    partial_.bottomRightCorner<3, 3>() += skew(forces.segment<3>(3 * node)) * skew(r);
  }
  matrix_ = partial_;
  return true;
}

Eigen::Matrix<double, 6, 1> PatchStiffness::column(FemBody& body, int group,
                                                   const Eigen::Vector3d& point, double tolerance,
                                                   int c) {
  const int n = body.model().nodeCount();
  const SystemOperator& system = body.stepper().system();
  const double dt = body.stepper().lastTimeStep();
  const double beta = body.model().material().stiffness_damping;
  const std::vector<int>& grabbed = body.groups()[static_cast<size_t>(group)]->nodes();
  const Eigen::VectorXd& x = body.state().positions;

  SolverSettings settings = body.stepper().settings();
  settings.tolerance = tolerance;
  zero_rhs_.setZero(3 * n);
  if (warm_.size() != 6 || warm_[0].size() != 3 * n) warm_.assign(6, Eigen::VectorXd::Zero(3 * n));

  // Unit twist over one step: velocities J e_c (the 1/dt is applied to the column at the end).
  NodeConstraints constraints(n);
  for (const auto& g : body.groups()) {
    for (int node : g->nodes())
      constraints.prescribeVelocity(node, Eigen::Vector3d::Zero());
  }
  for (int node : grabbed) {
    const Eigen::Vector3d r = x.segment<3>(3 * node) - point;
    const Eigen::Vector3d v =
        c < 3 ? Eigen::Vector3d::Unit(c) : Eigen::Vector3d(Eigen::Vector3d::Unit(c - 3).cross(r));
    constraints.prescribeVelocity(node, v);
  }
  Eigen::VectorXd& dv = warm_[static_cast<size_t>(c)];
  cg_.solve(system, constraints, zero_rhs_, settings, dv);
  system.multiplyStiffness(dv, stiffness_times_);
  Eigen::Matrix<double, 6, 1> out = Eigen::Matrix<double, 6, 1>::Zero();
  for (int node : grabbed) {
    const Eigen::Vector3d df = -(dt + beta) * stiffness_times_.segment<3>(3 * node);
    const Eigen::Vector3d r = x.segment<3>(3 * node) - point;
    out.head<3>() += df;
    out.tail<3>() += r.cross(df);
  }
  return out / dt;
}

}  // namespace torsion::haptics
