#include "torsion/solve/implicit_stepper.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hyperelastic_pass.h"
#include "system_operator_kernels.h"
#include "tet4_force_input.h"
#include "torsion/fem/corotated_element.h"
#include "torsion/fem/nodal_pressure.h"
#include "torsion/fem/polar_rotation.h"
#include "torsion/fem/quadratic_element.h"
#include "torsion/fem/volume_barrier.h"
#include "torsion/solve/cholmod_solver.h"

namespace torsion {

namespace {
constexpr int kTetGrain = 256;
}  // namespace

const char* toString(StepHealth health) {
  switch (health) {
    case StepHealth::kOk:
      return "ok";
    case StepHealth::kSolverNotConverged:
      return "solver not converged";
    case StepHealth::kContactNotConverged:
      return "contact not converged";
    case StepHealth::kSolverFailed:
      return "solver failed";
    case StepHealth::kNonFinite:
      return "non-finite state";
    case StepHealth::kBlowUp:
      return "blow-up";
  }
  return "?";
}

ImplicitStepper::ImplicitStepper(std::shared_ptr<const FemModel> model,
                                 const SolverSettings& settings, const Parallel& parallel)
    : model_(std::move(model)),
      settings_(settings),
      parallel_(parallel),
      system_(model_, parallel),
      hyperelastic_(std::make_unique<HyperelasticPass>(system_)),
      last_dt_(settings.time_step) {
  element_forces_.resize(static_cast<size_t>(model_->elementCount()) *
                         static_cast<size_t>(model_->nodesPerElement()));
  element_energy_.resize(static_cast<size_t>(model_->elementCount()));
}

ImplicitStepper::~ImplicitStepper() = default;

double ImplicitStepper::computeElasticForces(FemState& state) {
  if (model_->material().hyperelastic()) return computeHyperelasticForces(state);
  system_.setElementStiffnesses(nullptr);  // a live edit may have left the hyperelastic law
  system_.setLaggedStiffness(nullptr, 0.0);
  const double mu = model_->material().mu();
  const double lambda = model_->material().lambda();
  const std::vector<int>& nodes = model_->elementNodes();
  double nodal_energy = 0;
  if (model_->elementKind() == ElementKind::kTet4) {
    // The force pass also writes the rotated gradients K is assembled from (one pass over the
    // tets instead of two).
    const SystemOperator::RotationOutputs outputs = system_.mutableRotationsAndGradients();
    std::vector<Eigen::Matrix3d>& rotations = outputs.rotations;
    // Nodal pressure (fem/nodal_pressure.h): the tets carry the deviatoric stress (lambda ->
    // -2 mu / 3) and report their volumetric strain; the pressure comes from the node averages.
    const bool nodal_pressure = model_->nodalPressure();
    const double element_lambda = nodal_pressure ? -2.0 * mu / 3.0 : lambda;
    tet_strain_.resize(nodal_pressure ? nodes.size() / 4 : 0);
    // Four tets at a time in the operator's kernel build (system_operator_kernels.h); the tets it
    // flags (det F <= 0) go through the SVD path here.
    static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "12 doubles per tet");
    system_kernels::Tet4ForceInput in =
        tet4ForceInput(*model_, state, mu, element_lambda, outputs, needs_svd_);
    in.forces = element_forces_.data()->data();
    in.energy = element_energy_.data();
    in.volumetric_strain = nodal_pressure ? tet_strain_.data() : nullptr;
    parallel_.forRange(model_->elementCount(), kTetGrain, [&](int begin, int end) {
      system_.kernels().tet4_forces(in, begin, end);
      for (int t = begin; t < end; ++t) {
        const size_t ti = static_cast<size_t>(t);
        if (needs_svd_[ti] == 0) continue;
        const TetRestData& rest = model_->tetRestData()[ti];
        std::array<Eigen::Vector3d, 4> x;
        for (size_t a = 0; a < 4; ++a)
          x[a] = state.positions.segment<3>(3 * nodes[4 * ti + a]);
        const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
        rotations[ti] = extractRotation(F, state.element_rotations[ti]);
        const CorotatedResponse response =
            corotatedResponse(F, rotations[ti], rest, mu, element_lambda);
        std::copy(response.forces.begin(), response.forces.end(), element_forces_.begin() + 4 * t);
        element_energy_[ti] = response.energy;
        if (nodal_pressure) tet_strain_[ti] = (rotations[ti].transpose() * F).trace() - 3.0;
        system_.rotateGradients(t);
      }
    });
    if (nodal_pressure) nodal_energy = addNodalPressureForces();
  } else {
    // One rotation per element, from its mean deformation gradient (quadratic_element.h).
    std::vector<Eigen::Matrix3d>& rotations = system_.mutableRotations();
    parallel_.forRange(model_->elementCount(), kTetGrain / 4, [&](int begin, int end) {
      for (int e = begin; e < end; ++e) {
        const size_t ei = static_cast<size_t>(e);
        const QuadraticRestData& rest = model_->quadraticRestData()[ei];
        Tet10Vectors x;
        for (size_t a = 0; a < 10; ++a)
          x[a] = state.positions.segment<3>(3 * nodes[10 * ei + a]);
        rotations[ei] =
            extractRotation(quadraticCentroidGradient(x, rest), state.element_rotations[ei]);
        const QuadraticResponse response = quadraticResponse(x, rotations[ei], rest, mu, lambda);
        std::copy(response.forces.begin(), response.forces.end(), element_forces_.begin() + 10 * e);
        element_energy_[ei] = response.energy;
      }
    });
  }
  system_.gather(element_forces_, 1.0, elastic_forces_);
  double energy = nodal_energy + addVolumeBarrier(state);
  for (double e : element_energy_)
    energy += e;
  return energy;
}

double ImplicitStepper::addVolumeBarrier(const FemState& state) {
  barrier_tets_ = 0;
  const VolumeBarrier barrier = volumeBarrierOf(model_->material());
  if (!(barrier.threshold > 0 && barrier.pressure > 0)) return 0.0;
  const std::vector<Tet>& tets = model_->mesh().tets();
  const std::vector<TetRestData>& rest = model_->tetRestData();
  auto gradientOf = [&](size_t t) {
    std::array<Eigen::Vector3d, 4> x;
    for (size_t a = 0; a < 4; ++a)
      x[a] = state.positions.segment<3>(3 * tets[t][a]);
    return deformationGradient(x, rest[t].rest_shape_inverse);
  };
  // J = det(Ds) / det(Dm) = det(Ds) / (6 V): a triple product per tet, no F (this pass runs over
  // every tet every step; F is formed below only for the few tets under the threshold).
  volume_ratio_.resize(tets.size());
  const double* x = state.positions.data();
  parallel_.forRange(static_cast<int>(tets.size()), kTetGrain, [&](int begin, int end) {
    for (size_t t = static_cast<size_t>(begin); t < static_cast<size_t>(end); ++t) {
      const Tet& tet = tets[t];
      const Eigen::Map<const Eigen::Vector3d> x0(x + 3 * tet[0]);
      const Eigen::Vector3d e1 = Eigen::Map<const Eigen::Vector3d>(x + 3 * tet[1]) - x0;
      const Eigen::Vector3d e2 = Eigen::Map<const Eigen::Vector3d>(x + 3 * tet[2]) - x0;
      const Eigen::Vector3d e3 = Eigen::Map<const Eigen::Vector3d>(x + 3 * tet[3]) - x0;
      volume_ratio_[t] = e1.dot(e2.cross(e3)) / (6.0 * rest[t].volume);
    }
  });
  // Few tets are ever below the threshold (none at ordinary strains: then nothing below changes
  // a bit of the forces or of K), so the rest runs serially, in tet order.
  double energy = 0;
  std::vector<SystemOperator::SlotBlock> additions;
  for (size_t t = 0; t < tets.size(); ++t) {
    if (!barrier.active(volume_ratio_[t])) continue;
    ++barrier_tets_;
    const Eigen::Matrix3d F = gradientOf(t);
    const std::array<Eigen::Vector3d, 4> forces = volumeBarrierForces(F, rest[t], barrier);
    for (size_t a = 0; a < 4; ++a)
      elastic_forces_.segment<3>(3 * tets[t][a]) += forces[a];
    energy += volumeBarrierEnergy(F, rest[t], barrier);
    const TetStiffness K = volumeBarrierStiffness(F, rest[t], barrier);
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const int row = tets[t][static_cast<size_t>(a)];
        const int column = tets[t][static_cast<size_t>(b)];
        if (row > column) continue;  // stored as (column, row), the transposed block of (b, a)
        additions.push_back({system_.blockSlot(row, column), K.block<3, 3>(3 * a, 3 * b)});
      }
    }
  }
  system_.setStiffnessAdditions(std::move(additions));
  return energy;
}

double ImplicitStepper::addNodalPressureForces() {
  const int tets = model_->elementCount();
  node_strain_.resize(static_cast<size_t>(model_->nodeCount()));
  parallel_.forRange(model_->nodeCount(), kTetGrain, [&](int begin, int end) {
    averageOverNodeTets(*model_, tet_strain_, begin, end, node_strain_);
  });
  parallel_.forRange(tets, kTetGrain, [&](int begin, int end) {
    // tet_strain_ becomes the tet pressure pbar_e: each tet reads and writes only its own entry.
    averageOverTetNodes(*model_, node_strain_, model_->material().bulkModulus(), begin, end,
                        tet_strain_);
    addPressureForces(*model_, tet_strain_, system_.rotations(), begin, end, element_forces_);
  });
  return nodalVolumetricEnergy(*model_, node_strain_);
}

StepReport ImplicitStepper::step(FemState& state, const NodeConstraints& constraints,
                                 const Eigen::VectorXd& external_forces, double dt) {
  StepReport report = prepare(state, constraints, external_forces, dt);
  if (isFatal(report.health)) return report;
  report.solve = solve();
  finish(state, velocity_next_, report);
  return report;
}

StepReport ImplicitStepper::prepare(FemState& state, const NodeConstraints& constraints,
                                    const Eigen::VectorXd& external_forces, double dt) {
  StepReport report;
  internal_forces_valid_ = false;
  last_dt_ = dt;
  constraints_ = &constraints;
  report.elastic_energy = computeElasticForces(state);
  report.barrier_tets = barrier_tets_;
  // Non-finite b ends the step here: the system and the warm start's history stay the last step's.
  if (!buildRightHandSide(state, external_forces, dt, report)) return report;
  prepareSystem(state, dt);
  newton_ = NewtonReport{};
  linearized_ = false;
  if (model_->material().hyperelastic()) {
    start_positions_ = state.positions;
    start_velocities_ = state.velocities;
    step_external_forces_ = external_forces;
    newton_constraints_ = constraints.homogeneous();
  }
  return report;
}

PreparedSystem ImplicitStepper::prepared() {
  PreparedSystem p;
  p.op = &system_;
  p.constraints = constraints_;
  p.b = &rhs_;
  p.settings = &settings_;
  p.v = &velocity_next_;
  return p;
}

void ImplicitStepper::finish(FemState& state, const Eigen::Ref<const Eigen::VectorXd>& velocities,
                             StepReport& report) {
  // v' stays in velocity_next_: the internal forces and the next warm start read it.
  if (velocities.data() != velocity_next_.data()) velocity_next_ = velocities;
  if (linearized_ && internal_forces_valid_) {
    // The contacts moved the step off its free motion v*, where the Newton solve left the exact
    // internal forces: they follow the linearisation, -(dt + beta) K (v' - v*).
    system_.multiplyStiffness(velocity_next_ - free_velocity_, scratch_);
    internal_forces_ -= (last_dt_ + model_->material().stiffness_damping) * scratch_;
  }
  integratePositions(state, last_dt_);
  report.newton = newton_;
  checkHealth(state, report);
  if (!isFatal(report.health)) judgeNewton(report);
}

bool ImplicitStepper::buildRightHandSide(const FemState& state,
                                         const Eigen::VectorXd& external_forces, double dt,
                                         StepReport& report) {
  const std::vector<double>& mass = model_->nodeMasses();
  const int n = model_->nodeCount();
  rhs_.resize(3 * n);
  for (int i = 0; i < n; ++i) {
    rhs_.segment<3>(3 * i) =
        mass[static_cast<size_t>(i)] * state.velocities.segment<3>(3 * i) +
        dt * (elastic_forces_.segment<3>(3 * i) + external_forces.segment<3>(3 * i));
  }
  if (rhs_.allFinite()) return true;
  // Bad forces in, or a state already broken: stop before anything is written.
  report.health = StepHealth::kNonFinite;
  report.message =
      elastic_forces_.allFinite() && external_forces.allFinite()
          ? "non-finite velocities at the start of the step"
          : (elastic_forces_.allFinite() ? "non-finite external forces"
                                         : "non-finite elastic forces (a degenerate tet?)");
  return false;
}

void ImplicitStepper::prepareSystem(const FemState& state, double dt) {
  const Material& material = model_->material();
  system_.setCoefficients(1.0 + dt * material.mass_damping,
                          dt * dt + dt * material.stiffness_damping);
  // Warm start: extrapolate the velocity linearly from the last two steps (constant acceleration).
  if (previous_velocities_.size() == state.velocities.size()) {
    velocity_next_ = 2.0 * state.velocities - previous_velocities_;
  } else {
    velocity_next_ = state.velocities;
  }
  previous_velocities_ = state.velocities;
}

LinearSolveReport ImplicitStepper::solve() {
  if (model_->material().hyperelastic() && !linearized_) return solveNewton();
  if (settings_.linear_solver == LinearSolverKind::kCholmod) {
    if (!cholmod_) cholmod_ = std::make_unique<CholmodSolver>();
    return cholmod_->solve(system_, *constraints_, rhs_, velocity_next_);
  }
  return cg_.solve(system_, *constraints_, rhs_, settings_, velocity_next_);
}

void ImplicitStepper::integratePositions(FemState& state, double dt) const {
  state.velocities = velocity_next_;
  state.positions += dt * state.velocities;
}

void ImplicitStepper::checkHealth(const FemState& state, StepReport& report) const {
  const std::vector<double>& mass = model_->nodeMasses();
  double kinetic = 0, max_speed_sq = 0;
  for (int i = 0; i < model_->nodeCount(); ++i) {
    const double speed_sq = state.velocities.segment<3>(3 * i).squaredNorm();
    kinetic += 0.5 * mass[static_cast<size_t>(i)] * speed_sq;
    max_speed_sq = std::max(max_speed_sq, speed_sq);
  }
  report.kinetic_energy = kinetic;
  report.max_speed = std::sqrt(max_speed_sq);
  if (!std::isfinite(kinetic) || !state.positions.allFinite() ||
      !std::isfinite(report.elastic_energy)) {
    report.health = StepHealth::kNonFinite;
    report.message = "non-finite positions or velocities (NaN or inf)";
  } else if (report.max_speed > settings_.max_speed) {
    report.health = StepHealth::kBlowUp;
    std::ostringstream s;
    s << "a node moves at " << report.max_speed << " m/s, beyond max_speed " << settings_.max_speed
      << " m/s: the simulation is unstable (reduce dt or stiffness, or raise damping)";
    report.message = s.str();
  } else if (report.solve.breakdown || (!report.solve.converged && report.solve.relative_residual >
                                                                       10 * settings_.tolerance)) {
    // (A solve that reached what it was asked passes: a Newton direction may be asked for less
    // than the CG tolerance, solveNewton, and its Newton solve is judged by judgeNewton.)
    report.health = StepHealth::kSolverFailed;
    std::ostringstream s;
    s << "linear solver " << (report.solve.breakdown ? "broke down" : "did not converge")
      << " after " << report.solve.iterations << " iterations at relative residual "
      << report.solve.relative_residual
      << (report.solve.breakdown_reason ? std::string(": ") + report.solve.breakdown_reason : "")
      << " (tolerance " << settings_.tolerance << ", max_iterations " << settings_.max_iterations
      << "): the system is indefinite or badly conditioned; raise max_iterations, reduce dt, or "
         "use cholmod";
    report.message = s.str();
  } else if (!report.solve.converged) {
    report.health = StepHealth::kSolverNotConverged;
    std::ostringstream s;
    s << "linear solver stopped after " << report.solve.iterations
      << " iterations at relative residual " << report.solve.relative_residual << " > tolerance "
      << settings_.tolerance;
    report.message = s.str();
  }
}

const Eigen::VectorXd& ImplicitStepper::internalForces() {
  if (velocity_next_.size() != 3 * model_->nodeCount()) {
    // No step taken yet: the body is at rest in its initial state and exerts nothing.
    internal_forces_.setZero(3 * model_->nodeCount());
    return internal_forces_;
  }
  if (!internal_forces_valid_) {
    system_.multiplyStiffness(velocity_next_, scratch_);
    internal_forces_ =
        elastic_forces_ - (last_dt_ + model_->material().stiffness_damping) * scratch_;
    internal_forces_valid_ = true;
  }
  return internal_forces_;
}

const Eigen::VectorXd& ImplicitStepper::internalForcesAt(const std::vector<int>& nodes) {
  if (velocity_next_.size() != 3 * model_->nodeCount() || internal_forces_valid_)
    return internalForces();
  system_.multiplyStiffnessRows(velocity_next_, nodes, node_scratch_);
  node_forces_.resize(3 * model_->nodeCount());
  const double scale = last_dt_ + model_->material().stiffness_damping;  // as internalForces()
  for (int node : nodes) {
    node_forces_.segment<3>(3 * node) =
        elastic_forces_.segment<3>(3 * node) - scale * node_scratch_.segment<3>(3 * node);
  }
  return node_forces_;
}

ImplicitStepper::Memory ImplicitStepper::memory() {
  Memory m;
  m.internal_forces = internalForces();  // now, while K is the last step's
  m.previous_velocities = previous_velocities_;
  m.velocity_next = velocity_next_;
  m.elastic_forces = elastic_forces_;
  m.last_dt = last_dt_;
  return m;
}

void ImplicitStepper::restore(const Memory& memory) {
  previous_velocities_ = memory.previous_velocities;
  velocity_next_ = memory.velocity_next;
  elastic_forces_ = memory.elastic_forces;
  internal_forces_ = memory.internal_forces;
  internal_forces_valid_ = true;  // K is rebuilt at the next step; until then, the remembered ones
  last_dt_ = memory.last_dt;
}

void ImplicitStepper::replaceModel(std::shared_ptr<const FemModel> model) {
  internalForces();  // freeze the last step's forces before K and beta change under them
  model_ = std::move(model);
  system_.replaceModel(model_);
  hyperelastic_->forget();  // its stiffnesses are the old material's
}

}  // namespace torsion
