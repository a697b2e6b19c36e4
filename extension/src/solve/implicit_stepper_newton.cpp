// The hyperelastic half of ImplicitStepper (solve/implicit_stepper.h): the element pass at the
// step's start and the Newton solve of the incremental potential.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "hyperelastic_pass.h"
#include "system_operator_kernels.h"
#include "tet4_force_input.h"
#include "torsion/fem/corotated_element.h"
#include "torsion/fem/polar_rotation.h"
#include "torsion/fem/quadratic_element.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion {

namespace {
// Armijo's sufficient-decrease fraction and the line search's halvings before it gives up.
constexpr double kArmijo = 1e-4;
constexpr int kMaxHalvings = 12;
// Phi is a sum of thousands of terms: differences below this fraction of its terms' magnitude are
// rounding, and a step whose predicted decrease is that small is taken in full.
constexpr double kEnergyRounding = 1e-11;
// Each element's energy is a difference of terms of order mu V_e (the invariants against their
// rest values), so the summed elastic energy carries rounding of up to about eps mu V whatever its
// own size: measured 0.1 eps mu V on a 10 m beam at E = 1 GPa vibrating about rest, where that
// noise (1e-7 J) stopped the line search 300 times above the relative allowance. Four times the
// bound.
constexpr double kTermRounding = 4 * std::numeric_limits<double>::epsilon();
// Forces below this fraction of mu V^(2/3) (the force a unit strain gives the body) are rounding:
// a residual that small has converged whatever the step's scale (a body at rest has none).
constexpr double kForceRounding = 1e-12;
// Elements per task of the rotation pass.
constexpr int kRotationGrain = 256;
// K_0's rotations stop their quaternion iteration at this update (rad), where the corotated
// forces need 1e-6 (fem/polar_rotation.h): K_0 enters only the damping, whose share of the
// forces is small, and the system a later query linearises about. Measured on the 8332-tet
// twist at newton_tolerance 1e-4: the final positions move by 3.4e-7 of their displacement
// against 1e-6 (their deviation from the tight run stays 2.66e-5), and the pass takes a quarter
// less time.
constexpr double kRotationTolerance = 1e-4;

void addSolve(LinearSolveReport& total, const LinearSolveReport& solve) {
  total.iterations += solve.iterations;
  total.relative_residual = std::max(total.relative_residual, solve.relative_residual);
  total.converged = total.converged && solve.converged;
  if (solve.breakdown) {
    total.breakdown = true;
    total.breakdown_reason = solve.breakdown_reason;
  }
}
}  // namespace

double ImplicitStepper::computeHyperelasticForces(FemState& state) {
  // Forces and energy at x_n. The last step's final iterate is usually this step's start, and the
  // pass still holds its forces and energy (bit for bit what evaluating again gives).
  if (!hyperelastic_->holdsForcesAt(state.positions))
    hyperelastic_->evaluate(*model_, state.positions, parallel_, TetStiffnessKind::kNone);
  barrier_tets_ = hyperelastic_->barrierTets();
  system_.setStiffnessAdditions({});  // the pass holds the barrier (a live edit may leave some)
  // The last residual gathered these forces already when the pass has not evaluated since.
  if (gathered_evaluation_ == hyperelastic_->evaluations()) {
    elastic_forces_ = iterate_forces_;
  } else {
    system_.gather(hyperelastic_->elementForces(), 1.0, elastic_forces_);
  }
  // K_0's rotations (solveNewton): each element's at x_n, warm-started from its last as a
  // corotated body's: tet4 by the corotated force kernel (without its forces; four tets at a time,
  // and it writes the rotated gradients K_0's assembly reads), tet10 of its mean F.
  const std::vector<int>& nodes = model_->elementNodes();
  if (model_->elementKind() == ElementKind::kTet4) {
    const SystemOperator::RotationOutputs outputs = system_.mutableRotationsAndGradients();
    system_kernels::Tet4ForceInput in = tet4ForceInput(
        *model_, state, model_->material().mu(), model_->material().lambda(), outputs, needs_svd_);
    in.tolerance = kRotationTolerance;
    parallel_.forRange(model_->elementCount(), kRotationGrain, [&](int begin, int end) {
      system_.kernels().tet4_forces(in, begin, end);
      for (int t = begin; t < end; ++t) {
        const size_t ti = static_cast<size_t>(t);
        if (needs_svd_[ti] == 0) continue;  // inverted: the SVD's rotation
        std::array<Eigen::Vector3d, 4> x;
        for (size_t a = 0; a < 4; ++a)
          x[a] = state.positions.segment<3>(3 * nodes[4 * ti + a]);
        outputs.rotations[ti] =
            extractRotation(deformationGradient(x, model_->tetRestData()[ti].rest_shape_inverse),
                            state.element_rotations[ti]);
        system_.rotateGradients(t);
      }
    });
  } else {
    std::vector<Eigen::Matrix3d>& rotations = system_.mutableRotations();
    parallel_.forRange(model_->elementCount(), kRotationGrain / 4, [&](int begin, int end) {
      for (size_t e = static_cast<size_t>(begin); e < static_cast<size_t>(end); ++e) {
        Tet10Vectors x;
        for (size_t a = 0; a < 10; ++a)
          x[a] = state.positions.segment<3>(3 * nodes[10 * e + a]);
        rotations[e] = extractRotation(quadraticCentroidGradient(x, model_->quadraticRestData()[e]),
                                       state.element_rotations[e]);
      }
    });
  }
  return hyperelastic_->evaluatedEnergy();
}

LinearSolveReport ImplicitStepper::linearSolve(const NodeConstraints& constraints,
                                               const Eigen::VectorXd& b, Eigen::VectorXd& v,
                                               double tolerance) {
  if (settings_.linear_solver == LinearSolverKind::kCholmod) {
    if (!cholmod_) cholmod_ = std::make_unique<CholmodSolver>();
    return cholmod_->solve(system_, constraints, b, v);
  }
  SolverSettings settings = settings_;
  settings.tolerance = tolerance;
  return cg_.solve(system_, constraints, b, settings, v);
}

double ImplicitStepper::incrementalPotential(const Eigen::VectorXd& v, double elastic_energy,
                                             const Eigen::VectorXd& lagged_v) const {
  const Material& material = model_->material();
  const std::vector<double>& mass = model_->nodeMasses();
  double inertia = 0, mass_damping = 0;
  for (int i = 0; i < model_->nodeCount(); ++i) {
    const double m = mass[static_cast<size_t>(i)];
    inertia += m * (v.segment<3>(3 * i) - start_velocities_.segment<3>(3 * i)).squaredNorm();
    mass_damping += m * v.segment<3>(3 * i).squaredNorm();
  }
  double damping = material.mass_damping * mass_damping;
  if (material.stiffness_damping > 0) damping += material.stiffness_damping * v.dot(lagged_v);
  return 0.5 * inertia + 0.5 * last_dt_ * damping - last_dt_ * step_external_forces_.dot(v) +
         elastic_energy;
}

double ImplicitStepper::evaluateIterate(const Eigen::VectorXd& v, TetStiffnessKind stiffness) {
  trial_ = start_positions_ + last_dt_ * v;
  const double energy = hyperelastic_->evaluate(*model_, trial_, parallel_, stiffness);
  return iterateResidual(v, energy);
}

double ImplicitStepper::iterateResidual(const Eigen::VectorXd& v, double energy) {
  const Material& material = model_->material();
  const double dt = last_dt_;
  system_.gather(hyperelastic_->elementForces(), 1.0, iterate_forces_);
  gathered_evaluation_ = hyperelastic_->evaluations();
  if (material.stiffness_damping > 0) {
    system_.multiplyBlocks(start_stiffness_, v, lagged_product_);
  } else {
    lagged_product_.setZero(v.size());
  }
  // r = -grad Phi = M (v_n - v) - dt alpha M v - dt beta K_0 v + dt (f(x) + f_ext)
  const std::vector<double>& mass = model_->nodeMasses();
  newton_residual_.resize(v.size());
  for (int i = 0; i < model_->nodeCount(); ++i) {
    const double m = mass[static_cast<size_t>(i)];
    newton_residual_.segment<3>(3 * i) =
        m * (start_velocities_.segment<3>(3 * i) - v.segment<3>(3 * i)) -
        (dt * material.mass_damping * m) * v.segment<3>(3 * i) +
        dt * (iterate_forces_.segment<3>(3 * i) + step_external_forces_.segment<3>(3 * i) -
              material.stiffness_damping * lagged_product_.segment<3>(3 * i));
  }
  return incrementalPotential(v, energy, lagged_product_);
}

bool ImplicitStepper::lineSearch(Eigen::VectorXd& v, const Eigen::VectorXd& dv, double& phi) {
  const double slope = newton_residual_.dot(dv);  // -dPhi/dt at t = 0
  if (!(slope > 0)) return false;                 // not a descent direction
  // Each trial point is evaluated whole (forces with the energy: the accepted one, usually the
  // first, needs them for its residual); its stiffnesses only if the solve goes on from it.
  Eigen::VectorXd candidate;
  double t = 1;
  for (int halving = 0; halving <= kMaxHalvings; ++halving, t *= 0.5) {
    candidate = v + t * dv;
    const double trial_phi = evaluateIterate(candidate, TetStiffnessKind::kNone);
    const double rounding =
        kEnergyRounding * (std::abs(phi) + std::abs(hyperelastic_->evaluatedEnergy())) +
        kTermRounding * model_->material().mu() * model_->totalVolume();
    if (std::isfinite(trial_phi) && trial_phi <= phi - kArmijo * t * slope + rounding) {
      v = candidate;
      phi = trial_phi;
      newton_.line_search_cuts += halving;
      return true;
    }
  }
  newton_.line_search_cuts += kMaxHalvings;
  evaluateIterate(v, TetStiffnessKind::kNone);  // the step ends at v: its forces and residual
  return false;
}

LinearSolveReport ImplicitStepper::newtonDirection(const Eigen::VectorXd& free_residual,
                                                   double target, double scale,
                                                   Eigen::VectorXd& dv) {
  // Inexact Newton (Eisenstat and Walker 1996): a direction needs only the accuracy that brings
  // the residual to the target, so CG stops at |S r - A dv| <= eta |S r| with eta half the
  // target's share of |S r|, between the configured CG tolerance (never more accurate than a
  // corotated step's solve asks) and 1/2 (every direction a decrease). Measured on the 8332-tet
  // twist at newton_tolerance 1e-4: 3.9 CG iterations a step against 11.0 at the fixed tolerance,
  // one Newton direction a step either way (docs/materials.md, "Cost").
  const double residual = free_residual.norm();
  const double forcing = residual > 0
                             ? std::clamp(0.5 * target / residual, settings_.tolerance, 0.5)
                             : settings_.tolerance;
  // The exact Hessian first: where the step's system is positive definite with it (the usual case;
  // element Hessians are indefinite under finite shear, their sum plus M / dt^2 rarely is) Newton
  // converges quadratically, where a projected one converges only linearly (measured: 20-30
  // iterations for a quarter turn of the statics twist, docs/materials.md). Where the system is
  // not positive definite (the factorisation or CG breaks down) or dv is no descent direction,
  // the pass's positive semi-definite stiffness at the iterate, evaluated only then: the mirrored
  // one (negative eigenvalues replaced by their magnitudes), whose steps stay short where the
  // energy bends down and which, on the nearly incompressible twist, leaves the fallback after a
  // few iterations where the clamped one never does (docs/materials.md, "Validation on tet10").
  system_.setElementStiffnesses(&hyperelastic_->exactStiffnesses());
  dv.setZero(free_residual.size());
  // The step reports its solves' residuals against its own scale, as the linearised step's.
  const double to_scale = scale > 0 ? residual / scale : 1.0;
  LinearSolveReport exact = linearSolve(newton_constraints_, free_residual, dv, forcing);
  exact.relative_residual *= to_scale;
  if (!exact.breakdown && dv.allFinite() && newton_residual_.dot(dv) > 0) return exact;
  ++newton_.projected_iterations;
  if (!hyperelastic_->holdsProjectedAt(trial_))
    hyperelastic_->evaluate(*model_, trial_, parallel_, TetStiffnessKind::kMirrored);
  system_.setElementStiffnesses(&hyperelastic_->projectedStiffnesses());
  dv.setZero(free_residual.size());
  LinearSolveReport projected = linearSolve(newton_constraints_, free_residual, dv, forcing);
  projected.relative_residual *= to_scale;
  projected.iterations += exact.iterations;
  return projected;
}

bool ImplicitStepper::predictionFits() const {
  // The prediction moves every prescribed node to within 1 % of the mean element size of its
  // target over the step: then the first Newton step from it is a small correction (measured:
  // 1.03 directions a step on the dynamic twist), where a start that leaves the prescribed motion
  // to the first iterate alone (a statics increment, a jerked hand) shears the elements next to
  // those nodes, and the linearised step spreads it over the body instead (measured: 16-27
  // statics iterations from the prediction against 10-19 from the linearised step).
  Eigen::VectorXd imposed = velocity_next_;
  constraints_->impose(imposed);
  const double rest_volume = model_->totalMass() / model_->material().density;
  const double element_size = std::cbrt(rest_volume / model_->elementCount());
  return last_dt_ * (imposed - velocity_next_).lpNorm<Eigen::Infinity>() <= 0.01 * element_size;
}

LinearSolveReport ImplicitStepper::solveNewton() {
  const Material& material = model_->material();
  const double dt = last_dt_;
  Eigen::VectorXd& v = velocity_next_;
  // The first iterate: the predicted velocity (the warm start's extrapolation) with the prescribed
  // velocities imposed, when that fits (predictionFits); else the linearised step at x_n, solved
  // in full with K_0. Either way held and carried nodes land exactly on their targets (every later
  // direction is zero there). K_0 is the corotated stiffness of the material's small-strain moduli
  // at x_n (computeHyperelasticForces): positive semi-definite, rotation-invariant and the
  // material's tangent at small strain, it is the Rayleigh damping's (held for the step, so that
  // Phi is a true potential) and the system a later query linearises about (PatchStiffness, the
  // haptic K_h), without the SVD and the 12x12 products the projected Hessian costs per element.
  const bool predicted = predictionFits();
  double energy = 0;
  if (predicted) {
    constraints_->impose(v);
    trial_ = start_positions_ + dt * v;
    energy = hyperelastic_->evaluate(*model_, trial_, parallel_, TetStiffnessKind::kExact);
  }
  system_.setElementStiffnesses(nullptr);
  system_.setLaggedStiffness(nullptr, 0.0);
  // The residual scale: the step's first system's |S(b - A v_prescribed)| (what the step must
  // move, as the CG measures it) plus dt |f(x_n)| (the impulse of the elastic forces now,
  // reactions on held nodes included, which stays the scale of a body held still in a deformed
  // equilibrium).
  Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(rhs_.size());
  constraints_->impose(prescribed);
  constraints_->constrainedNodes(constrained_nodes_);
  system_.multiplyFromNodes(prescribed, constrained_nodes_, scratch_);
  Eigen::VectorXd free_rhs = rhs_ - scratch_;
  constraints_->filter(free_rhs);
  const double reference = free_rhs.norm() + dt * elastic_forces_.norm();
  LinearSolveReport total;
  total.converged = true;
  newton_.iterations = 0;
  if (!predicted) {
    total = linearSolve(*constraints_, rhs_, v, settings_.tolerance);
    newton_.iterations = 1;
  }
  if (material.stiffness_damping > 0) system_.takeStiffnessBlocks(start_stiffness_);
  system_.setCoefficients(1.0 + dt * material.mass_damping, dt * dt);
  system_.setLaggedStiffness(material.stiffness_damping > 0 ? &start_stiffness_ : nullptr,
                             material.stiffness_damping / dt);
  double phi =
      predicted ? iterateResidual(v, energy) : evaluateIterate(v, TetStiffnessKind::kExact);
  Eigen::VectorXd free_residual;
  const double rest_volume = model_->totalMass() / material.density;
  const double rounding =
      kForceRounding * dt * material.mu() * std::cbrt(rest_volume * rest_volume);
  Eigen::VectorXd dv;
  while (!total.breakdown) {
    free_residual = newton_residual_;
    newton_constraints_.filter(free_residual);
    const double residual = free_residual.norm();
    newton_.relative_residual = reference > 0 ? residual / reference : residual;
    const double target = settings_.newton_tolerance * reference + rounding;
    newton_.converged = residual <= target;
    if (newton_.converged || newton_.iterations >= settings_.newton_max_iterations) break;
    if (!hyperelastic_->holdsExactAt(trial_))
      hyperelastic_->evaluate(*model_, trial_, parallel_, TetStiffnessKind::kExact);
    addSolve(total, newtonDirection(free_residual, target, reference, dv));
    ++newton_.iterations;
    if (total.breakdown) break;
    if (!lineSearch(v, dv, phi)) {
      newton_.line_search_failed = true;
      break;
    }
  }
  if (total.breakdown) newton_.converged = false;
  // The operator goes back to the step's system (K_0, as a corotated body's holds its step's K):
  // what a later query of it (PatchStiffness, the haptic K_h) linearises about.
  system_.setElementStiffnesses(nullptr);
  system_.setLaggedStiffness(nullptr, 0.0);
  system_.setCoefficients(1.0 + dt * material.mass_damping,
                          dt * dt + dt * material.stiffness_damping);
  // Exact internal forces at the end of the step: f(x') - beta K_0 v'.
  internal_forces_ = iterate_forces_ - material.stiffness_damping * lagged_product_;
  internal_forces_valid_ = true;
  return total;
}

LinearSolveReport ImplicitStepper::linearizeAboutFreeMotion() {
  const LinearSolveReport free = solveNewton();
  linearized_ = true;
  free_velocity_ = velocity_next_;
  if (free.breakdown || !velocity_next_.allFinite()) return free;
  // The contact solve minimises the convex quadratic of the step's system about the free motion,
  // with K_0, the stiffness the free motion's damping used: with the damping's stiffness the same
  // on both sides, a body at rest on a contact rests where its elastic forces balance the load
  // (measured: a neo-Hookean ball's sag within 1.5 % of the corotated ball's, against 5 % with
  // the projected Hessian at the free motion's end on the contact side). K_h and the internal
  // forces' correction linearise with the same K_0.
  system_.multiply(velocity_next_, rhs_);
  return free;
}

void ImplicitStepper::judgeNewton(StepReport& report) const {
  const NewtonReport& n = report.newton;
  if (n.converged) return;
  std::ostringstream s;
  s << "Newton solve "
    << (n.line_search_failed ? "stalled (no decrease along its direction)"
                             : "stopped at its iteration cap")
    << " after " << n.iterations << " iterations at relative residual " << n.relative_residual
    << " (newton_tolerance " << settings_.newton_tolerance << ", newton_max_iterations "
    << settings_.newton_max_iterations << ")";
  const bool close = n.relative_residual <= 10 * settings_.newton_tolerance;
  if (close) {
    if (report.health == StepHealth::kOk) report.health = StepHealth::kSolverNotConverged;
  } else {
    report.health = StepHealth::kSolverFailed;
    s << ": the step is not a backward-Euler step; reduce dt or raise newton_max_iterations";
  }
  report.message += (report.message.empty() ? "" : "; ") + s.str();
}

}  // namespace torsion
