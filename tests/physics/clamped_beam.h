#pragma once
// The cantilever of the beam tests: a box beam 10 x 1 x 1 m along x on a structured mesh of
// 10 n x n x n cells, clamped at x = 0, loaded by gravity along -z. Two clamps:
//  - kFull: every node of the end face fixed. It also stops the end section's Poisson
//    contraction, which beam theory leaves free; the stiffening that adds grows with nu.
//  - kPlaneSection: the end face's nodes held in x only (the section stays plane and normal to
//    the axis), the neutral-axis row z = h/2 on it fixed (no rigid motion). The section contracts
//    freely, as beam theory assumes (needs an even cell count across for the mid-height row).
//    Quasi-statics (1 s steps, the
// velocity zeroed after each: damped Newton on the static equilibrium, M / dt^2 is 1e-9 of K at
// E = 1 GPa) or dynamics (any dt).

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <vector>

#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion::test {

enum class Clamp { kFull, kPlaneSection };

struct BeamSpec {
  double length = 10, side = 1;  ///< m
  Clamp clamp = Clamp::kFull;
  int cells_across = 4;  ///< n: 10 n x n x n cells
  Material material = defaultMaterial();
  ElementKind element = ElementKind::kTet4;
  SolverSettings solver = quasiStatic();
  double gravity = 9.81;  ///< m/s^2 along -z

  static Material defaultMaterial() {
    Material m;
    m.youngs_modulus = 1e9;
    m.poisson_ratio = 0.3;
    m.density = 1000;
    return m;
  }
  static SolverSettings quasiStatic() {
    SolverSettings s;
    s.time_step = 1.0;
    s.linear_solver = LinearSolverKind::kCholmod;
    return s;
  }
};

/// Euler-Bernoulli tip deflection under the beam's weight, q L^4 / (8 E I), q = rho g A.
inline double eulerBernoulliTip(const BeamSpec& spec) {
  const double q = spec.material.density * spec.gravity * spec.side * spec.side;
  const double I = std::pow(spec.side, 4) / 12;
  return q * std::pow(spec.length, 4) / (8 * spec.material.youngs_modulus * I);
}
/// Timoshenko: plus the shear deflection q L^2 / (2 k G A), shear coefficient k = 5/6 (a
/// rectangle; Cowper's nu-dependent 10 (1 + nu) / (12 + 11 nu) differs by < 2 % of the shear
/// term, i.e. < 0.03 % of the tip, for nu in [0.3, 0.5)). The shear term is 1.0 % (nu = 0.3) to
/// 1.2 % (nu = 0.5) of the bending one at L / h = 10.
inline double timoshenkoTip(const BeamSpec& spec) {
  const double q = spec.material.density * spec.gravity * spec.side * spec.side;
  return eulerBernoulliTip(spec) +
         q * spec.length * spec.length /
             (2 * (5.0 / 6.0) * spec.material.mu() * spec.side * spec.side);
}

class ClampedBeam {
 public:
  explicit ClampedBeam(const BeamSpec& spec)
      : spec_(spec),
        model_(FemModel::create(
                   std::make_shared<TetMesh>(
                       makeBoxTetMesh(Eigen::Vector3d::Zero(),
                                      Eigen::Vector3d(spec.length, spec.side, spec.side),
                                      10 * spec.cells_across, spec.cells_across, spec.cells_across)
                           .value()),
                   spec.material, spec.element)
                   .value()),
        parallel_(0),
        stepper_(model_, spec.solver, parallel_),
        state_(FemState::atRest(*model_)),
        constraints_(model_->nodeCount()),
        gravity_(3 * model_->nodeCount()) {
    const std::vector<Eigen::Vector3d>& rest = model_->mesh().restPositions();  // all nodes
    for (int i = 0; i < model_->nodeCount(); ++i) {
      gravity_.segment<3>(3 * i) =
          model_->nodeMasses()[static_cast<size_t>(i)] * Eigen::Vector3d(0, 0, -spec.gravity);
      const double x = rest[static_cast<size_t>(i)].x();
      const bool neutral_axis = std::abs(rest[static_cast<size_t>(i)].z() - spec.side / 2) < 1e-9;
      if (x < 1e-9 && (spec.clamp == Clamp::kFull || neutral_axis)) {
        constraints_.prescribeVelocity(i, Eigen::Vector3d::Zero());
      } else if (x < 1e-9) {
        constraints_.prescribeDirection(i, Eigen::Vector3d::UnitX(), 0.0);
      }
      if (x > spec.length - 1e-9) tip_.push_back(i);
    }
  }

  /// One step; returns its report.
  StepReport step() { return stepper_.step(state_, constraints_, gravity_); }
  /// One step without the load (the beam released).
  StepReport stepUnloaded() {
    return stepper_.step(state_, constraints_, Eigen::VectorXd::Zero(gravity_.size()));
  }
  FemState& state() { return state_; }
  ImplicitStepper& stepper() { return stepper_; }

  /// Quasi-static loading until the tip's vertical deflection changes by < 1e-9 relative (at most
  /// 30 steps); returns the last step's report.
  StepReport solveStatics() {
    StepReport report;
    double deflection = 0, previous = -1;
    for (int k = 0; k < 30 && std::abs(deflection - previous) > 1e-9 * std::abs(deflection); ++k) {
      previous = deflection;
      report = step();
      if (isFatal(report.health)) return report;
      state_.velocities.setZero();  // keep only the configuration
      deflection = -tipDisplacement().z();
    }
    return report;
  }

  /// Mean displacement of the tip face's nodes, m.
  Eigen::Vector3d tipDisplacement() const {
    const std::vector<Eigen::Vector3d>& rest = model_->mesh().restPositions();
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int i : tip_)
      sum += state_.position(i) - rest[static_cast<size_t>(i)];
    return sum / static_cast<double>(tip_.size());
  }

  const FemModel& model() const { return *model_; }
  const std::shared_ptr<const FemModel>& sharedModel() const { return model_; }
  const BeamSpec& spec() const { return spec_; }

 private:
  BeamSpec spec_;
  std::shared_ptr<const FemModel> model_;
  Parallel parallel_;
  ImplicitStepper stepper_;
  FemState state_;
  NodeConstraints constraints_;
  Eigen::VectorXd gravity_;
  std::vector<int> tip_;
};

}  // namespace torsion::test
