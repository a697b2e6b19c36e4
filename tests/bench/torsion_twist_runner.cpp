// Our side of the cylinder twist: torsion::ImplicitStepper, driven ends as prescribed velocities
// through NodeConstraints (the same mechanism as twistedRun in implicit_stepper_test.cpp).
// TwistProtocol::Law::kNeoHookean sets Material::law = kStableNeoHookean (same E, nu, rho and
// Rayleigh damping); the stepper then takes its Newton step by itself (docs/materials.md). The end
// torque is drivenTorqueZ of ImplicitStepper::internalForcesAt(driven) after the step, outside
// the timing: elastic + stiffness-damping forces at the end of the step (exact for the
// hyperelastic law, f(x') - beta K_n v'; linearised for the corotated one,
// f(x) - (dt + beta) K v').

#include <chrono>
#include <cmath>
#include <sstream>

#include "torsion/fem/fem_model.h"
#include "torsion/fem/material.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/implicit_stepper.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/parallel.h"
#include "torsion/solve/solver_settings.h"
#include "twist_protocol.h"

namespace torsion::bench {

TwistResult runTorsionTwist(const TwistProtocol& protocol, std::shared_ptr<const TetMesh> mesh,
                            const TorsionOptions& options) {
  using Clock = std::chrono::steady_clock;
  TwistResult result;
  const Clock::time_point setup_start = Clock::now();

  Material material;
  material.youngs_modulus = protocol.youngs_modulus;
  material.poisson_ratio = protocol.poisson_ratio;
  material.density = protocol.density;
  material.mass_damping = 0;
  material.stiffness_damping = protocol.stiffness_damping;
  if (protocol.law == TwistProtocol::Law::kNeoHookean)
    material.law = MaterialLaw::kStableNeoHookean;
  auto created =
      FemModel::create(mesh, material, options.tet10 ? ElementKind::kTet10 : ElementKind::kTet4);
  if (!created.ok()) {
    result.status = RunStatus::kSetupFailed;
    result.message = created.error().message;
    return result;
  }
  const std::shared_ptr<const FemModel> model = created.value();

  SolverSettings settings;
  settings.time_step = protocol.time_step;
  settings.linear_solver =
      options.cholmod ? LinearSolverKind::kCholmod : LinearSolverKind::kConjugateGradient;
  settings.tolerance = options.tolerance;
  settings.preconditioner = options.preconditioner;
  settings.refactor_interval = options.refactor_interval;
  settings.refactor_iterations = options.refactor_iterations;
  settings.newton_tolerance = options.newton_tolerance;
  settings.threads = options.threads;
  settings.max_speed = protocol.max_speed;
  if (Status valid = settings.validate(); !valid.ok()) {
    result.status = RunStatus::kSetupFailed;
    result.message = valid.error().message;
    return result;
  }
  std::ostringstream detail;
  if (options.cholmod) {
    detail << "cholmod";
  } else {
    detail << "cg " << toString(settings.preconditioner) << " tol " << settings.tolerance;
  }
  if (material.hyperelastic()) {
    detail << ", " << toString(material.law) << " newton tol " << settings.newton_tolerance;
  }
  detail << (options.tet10 ? ", tet10" : "") << ", threads " << options.threads;
  result.solver_detail = detail.str();

  const Parallel parallel(options.threads);
  ImplicitStepper stepper(model, settings, parallel);
  FemState state = FemState::atRest(*model);
  const int n = model->nodeCount();
  // tet10: the protocol's nodes are all P2 nodes (the model's mesh; the linear mesh for tet4).
  const TetMesh& nodes_mesh = model->mesh();
  const TwistScene scene = classifyNodes(nodes_mesh);
  std::vector<int> driven;
  NodeConstraints constraints(n);
  for (int i = 0; i < n; ++i) {
    const NodeRole role = scene.roles[static_cast<size_t>(i)];
    if (role == NodeRole::kFixed) constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
    if (role == NodeRole::kDriven) driven.push_back(i);
  }
  const Eigen::VectorXd external = Eigen::VectorXd::Zero(3 * n);
  const std::vector<Eigen::Vector3d>& rest = nodes_mesh.restPositions();
  const double dt = protocol.time_step;
  result.setup_seconds = std::chrono::duration<double>(Clock::now() - setup_start).count();
  result.setup_rss_kb = peakRssKb();

  result.step_ms.reserve(static_cast<size_t>(protocol.total_steps));
  result.step_iterations.reserve(static_cast<size_t>(protocol.total_steps));
  if (material.hyperelastic())
    result.step_newton.reserve(static_cast<size_t>(protocol.total_steps));
  double outside_cpu = 0;  // CPU seconds of the torque curve, taken out of the loop's CPU time
  const double cpu_start = processCpuSeconds();
  for (int k = 0; k < protocol.total_steps; ++k) {
    const Clock::time_point t0 = Clock::now();
    const double angle = protocol.angle((k + 1) * dt);
    for (int i : driven) {
      const Eigen::Vector3d target = turnedAboutZ(rest[static_cast<size_t>(i)], angle);
      constraints.prescribeVelocity(i, (target - state.position(i)) / dt);
    }
    const StepReport report = stepper.step(state, constraints, external);
    const Clock::time_point t1 = Clock::now();
    result.step_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
    result.step_iterations.push_back(report.solve.iterations);
    if (material.hyperelastic()) {
      result.step_newton.push_back(report.newton.iterations);
      if (!report.newton.converged) ++result.newton_not_converged_steps;
      result.line_search_cuts += report.newton.line_search_cuts;
      result.projected_iterations += report.newton.projected_iterations;
    }
    result.steps_done = k + 1;
    result.max_speed = std::max(result.max_speed, report.max_speed);
    if (report.health == StepHealth::kSolverNotConverged) ++result.not_converged_steps;
    if (isFatal(report.health)) {
      result.status = report.health == StepHealth::kNonFinite ? RunStatus::kNonFinite
                      : report.health == StepHealth::kBlowUp  ? RunStatus::kBlowUp
                                                              : RunStatus::kSolverFailed;
      result.message = "step " + std::to_string(k) + ": " + report.message;
      break;
    }
    if (protocol.record_curve) {
      const double c0 = processCpuSeconds();
      result.curve.push_back(
          {k + 1, angle, drivenTorqueZ(state.positions, stepper.internalForcesAt(driven), driven)});
      outside_cpu += processCpuSeconds() - c0;
    }
  }
  result.loop_cpu_seconds = processCpuSeconds() - cpu_start - outside_cpu;
  if (result.status == RunStatus::kOk) {
    result.end_torque = drivenTorqueZ(state.positions, stepper.internalForcesAt(driven), driven);
  }
  result.peak_rss_kb = peakRssKb();
  result.final_positions = state.positions;
  measureTwist(protocol, nodes_mesh, scene, state.positions, result);
  return result;
}

}  // namespace torsion::bench
