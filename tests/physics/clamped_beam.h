#pragma once
// The cantilever of the beam tests: a box beam 10 x 1 x 1 m along x on a structured mesh of
// 10 n x n x n cells, clamped at x = 0, loaded by gravity along -z. Quasi-statics (1 s steps, the
// velocity zeroed after each: damped Newton on the static equilibrium, M / dt^2 is 1e-9 of K at
// E = 1 GPa) or dynamics (any dt).

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <vector>

#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion::test {

struct BeamSpec {
  double length = 10, side = 1;  ///< m
  int cells_across = 4;          ///< n: 10 n x n x n cells
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

class ClampedBeam {
 public:
  explicit ClampedBeam(const BeamSpec& spec)
      : spec_(spec),
        model_(FemModel::create(std::make_shared<TetMesh>(
                                    makeBoxTetMesh(Eigen::Vector3d::Zero(),
                                                   Eigen::Vector3d(spec.length, spec.side, spec.side),
                                                   10 * spec.cells_across, spec.cells_across,
                                                   spec.cells_across)
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
      if (x < 1e-9) constraints_.prescribeVelocity(i, Eigen::Vector3d::Zero());
      if (x > spec.length - 1e-9) tip_.push_back(i);
    }
  }

  /// One step; returns its report.
  StepReport step() { return stepper_.step(state_, constraints_, gravity_); }

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
  const BeamSpec& spec() const { return spec_; }

  /// Euler-Bernoulli tip deflection under the beam's weight, q L^4 / (8 E I), q = rho g A.
  double eulerBernoulliTip() const {
    const double q = spec_.material.density * spec_.gravity * spec_.side * spec_.side;
    const double I = std::pow(spec_.side, 4) / 12;
    return q * std::pow(spec_.length, 4) / (8 * spec_.material.youngs_modulus * I);
  }
  /// Timoshenko: plus the shear deflection q L^2 / (2 kappa G A), kappa = 5/6 (rectangle).
  double timoshenkoTip() const {
    const double q = spec_.material.density * spec_.gravity * spec_.side * spec_.side;
    return eulerBernoulliTip() + q * spec_.length * spec_.length /
                                     (2 * (5.0 / 6.0) * spec_.material.mu() * spec_.side *
                                      spec_.side);
  }

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
