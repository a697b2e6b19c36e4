#pragma once
// One linearised backward-Euler step of one FEM body (Baraff & Witkin 1998; the report's
// integrator), as stages the caller drives: prepare() (1-3, and the system of 4), a solve of
// that system (the stepper's own solve(), or a contact solve run by the caller on
// prepared()), finish() (5-6). step() is prepare, solve, finish for a body stepped alone. Each
// stage is a function of its own:
//
//   1-2. computeElasticForces  per element, in one pass: F = Ds Bm (tet4) or the element's mean F
//                              (tet10), its rotation R (warm-started polar decomposition), and the
//                              elastic forces f(x) = -Re Ke (Re^T x - X); gathered per node;
//                              elastic energy; the volume barrier of the tets near inversion
//                              (fem/volume_barrier.h) adds its forces, energy and stiffness
//   3. buildRightHandSide      b = M v + dt (f(x) + f_ext); a non-finite b ends the step in
//                              prepare(), before the state is touched
//      prepareSystem           the system's coefficients and the warm start of v'
//   4. solve                   (M (1 + dt alpha) + (dt^2 + dt beta) K) v' = b, warm-started,
//                              prescribed components of v' imposed (projection), free ones solved
//                              by CG or CHOLMOD; with contacts the caller solves prepared()
//                              instead (contact/rigid_contact.h, contact/self_contact.h,
//                              contact/island_contact.h)
//   5. integratePositions      x' = x + dt v'   (constrained nodes land exactly on their targets)
//   6. checkHealth             non-finite values, speeds beyond SolverSettings::max_speed, a
//                              linear solve that broke down or stopped above 10x its tolerance
//                              (fatal), or one that stopped at its cap within 10x (a warning)
//
// Internal forces at the end of the step (what the body exerts on whatever holds its nodes) are
// available afterwards, linearised: f_int = f(x) - (dt + beta) K v'.
//
// Hyperelastic bodies (Material::law; docs/materials.md, "Time step") take the same stages with
// the hyperelastic element pass (positive semi-definite per-tet stiffness, K assembled from it),
// and solve() is a Newton solve of backward Euler's incremental potential in v (x = x_n + dt v)
//   Phi(v) = 1/2 |v - v_n|_M^2 + dt/2 v^T C v - dt f_ext . v + Psi(x_n + dt v),
//   C = alpha M + beta K_n (K_n: the stiffness at the step's start),
// whose minimiser is the backward-Euler step M (v - v_n) = dt (f(x) + f_ext - C v). Iteration 0
// is the prepared linearised step (taken in full, so prescribed nodes land on their targets);
// each further iteration solves (M (1 + dt alpha) + dt beta K_n + dt^2 K(x)) dv = S r(v) with the
// prescribed components of dv zero (the same CG or CHOLMOD), K(x) the exact Hessian or, where
// that system is not positive definite, the projected one, and backtracks along dv until Phi
// decreases enough (Armijo). It stops when |S r| <= newton_tolerance (|S(b - A v_prescribed)| +
// dt |f(x_n)|) (SolverSettings); StepReport::newton says how it went, and an unconverged step is
// a warning within 10x the tolerance and fatal above. Internal forces are then exact at the end
// of the step, f_int = f(x') - beta K_n v', and the operator (system()) holds the step's first
// system again, with K_n.

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "torsion/fem/fem_model.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/parallel.h"
#include "torsion/solve/projected_cg.h"
#include "torsion/solve/solver_settings.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

class CholmodSolver;
class HyperelasticPass;
enum class TetStiffnessKind;  // fem/hyperelastic.h

/// The Newton solve of a hyperelastic body's step (all zero for corotated bodies).
struct NewtonReport {
  int iterations = 0;  ///< Newton directions (linear solves); 0: the predicted velocity solved it
  /// |S r| of the accepted iterate over its scale, |S(b - A v_prescribed)| of the step's first
  /// system plus dt |f(x_n)| (SolverSettings::newton_tolerance).
  double relative_residual = 0;
  bool converged = true;
  int line_search_cuts = 0;  ///< step halvings, over all iterations
  /// Iterations whose direction took the projected Hessian (the exact one was not positive
  /// definite on the free dofs, or gave no descent).
  int projected_iterations = 0;
  /// The line search found no decrease of Phi along a direction (then converged is false).
  bool line_search_failed = false;
};

enum class StepHealth {
  kOk,
  kSolverNotConverged,  ///< CG hit its cap within 10x tolerance: usable but inaccurate (warning)
  /// Self-contact's multipliers stopped at their cap with end gaps beyond the tolerance: usable,
  /// the penetration is in the message and the contact statistics (warning; set by FemBody).
  kContactNotConverged,
  kSolverFailed,  ///< breakdown, or CG stuck far above tolerance: the step is meaningless
  kNonFinite,     ///< NaN or inf in positions or velocities: the state is unusable
  kBlowUp,        ///< a node moves faster than max_speed: unstable
};
const char* toString(StepHealth health);
inline bool isFatal(StepHealth h) {
  return h == StepHealth::kNonFinite || h == StepHealth::kBlowUp || h == StepHealth::kSolverFailed;
}

struct StepReport {
  LinearSolveReport solve;  ///< hyperelastic bodies: every Newton iteration's solves together
  NewtonReport newton;
  double elastic_energy = 0;  ///< J, at the start of the step (the volume barrier's included)
  /// Tets below the volume barrier's threshold at the start of the step (fem/volume_barrier.h).
  int barrier_tets = 0;
  double kinetic_energy = 0;  ///< J, at the end of the step
  double max_speed = 0;       ///< m/s, at the end of the step
  StepHealth health = StepHealth::kOk;
  std::string message;  ///< what went wrong, for the user
};

/// The linear system of a prepared step (ImplicitStepper::prepare), what any solve of it needs:
/// A v' = b, the prescribed components of v' imposed. Valid until the stepper's next prepare().
struct PreparedSystem {
  /// A = M (1 + dt alpha) + (dt^2 + dt beta) K.
  const SystemOperator* op = nullptr;
  const NodeConstraints* constraints = nullptr;  ///< the ones given to prepare() (the caller's)
  const Eigen::VectorXd* b = nullptr;            ///< M v + dt (f(x) + f_ext), 3n
  const SolverSettings* settings = nullptr;      ///< the stepper's (tolerance, iterations)
  /// The warm start 2 v_n - v_(n-1) (v_n on the first step), 3n: the solves write v' over it.
  Eigen::VectorXd* v = nullptr;
};

class ImplicitStepper {
 public:
  ImplicitStepper(std::shared_ptr<const FemModel> model, const SolverSettings& settings,
                  const Parallel& parallel);
  ~ImplicitStepper();
  ImplicitStepper(const ImplicitStepper&) = delete;
  ImplicitStepper& operator=(const ImplicitStepper&) = delete;

  /// Advances `state` by one step of `dt` seconds: prepare(), solve(), finish(). external_forces:
  /// 3n, N (e.g. m g per node). Non-finite forces are caught before the state is touched; on any
  /// fatal report callers stop and report instead of writing the state out. Inside a Bullet world
  /// dt is the world's substep (StepContext::dt) and may change from one step to the next.
  StepReport step(FemState& state, const NodeConstraints& constraints,
                  const Eigen::VectorXd& external_forces, double dt);
  /// A stepper used on its own (tests, benchmarks): one step of settings().time_step.
  StepReport step(FemState& state, const NodeConstraints& constraints,
                  const Eigen::VectorXd& external_forces) {
    return step(state, constraints, external_forces, settings_.time_step);
  }

  // ---- a step in stages, driven by the caller (FemBody: contacts solve the prepared system) ----
  /// Stages 1-3: forces at `state`, b, the system's coefficients and the warm start of v'
  /// (prepared()). `constraints` must live until finish(). Returns the report so far: on a fatal
  /// one (non-finite b) the step ends here, the state untouched, and finish() is not called.
  StepReport prepare(FemState& state, const NodeConstraints& constraints,
                     const Eigen::VectorXd& external_forces, double dt);
  /// The prepared step's system and its warm start (valid until the next prepare()).
  PreparedSystem prepared();
  /// Stage 4 without contacts: CG or CHOLMOD (settings().linear_solver) on the prepared system,
  /// v' over prepared().v (a hyperelastic body: its Newton solve, unless linearised below).
  LinearSolveReport solve();
  /// A hyperelastic body that may touch something, after prepare(): the step solved without its
  /// contacts (Newton: the free motion v*), then the prepared system made the step's potential
  /// linearised about v*: K the projected stiffness at x_n + dt v*, b = A v*, the warm start v*.
  /// A contact solve of that system with the contact rows is one Newton step from v* with the
  /// contacts (docs/contact.md, "Hyperelastic bodies"); solve() of it alone gives v* back. Returns
  /// the Newton solve's report (a breakdown: the step cannot go on).
  LinearSolveReport linearizeAboutFreeMotion();
  /// Stages 5-6: v = v' (`velocities`, 3n, from any solve of the prepared system; may be
  /// *prepared().v itself), x += dt v', and the health into `report`: prepare()'s, with
  /// report.solve set to that solve's report (a broken-down or unconverged solve is judged here).
  void finish(FemState& state, const Eigen::Ref<const Eigen::VectorXd>& velocities,
              StepReport& report);

  /// s, the length of the last step taken (settings().time_step before the first).
  double lastTimeStep() const { return last_dt_; }

  /// Elastic + stiffness-damping forces on each node at the end of the last step, 3n, N.
  const Eigen::VectorXd& internalForces();
  /// internalForces() needed at `nodes` only (a node group's wrench): a 3n vector whose rows at
  /// those nodes hold bit for bit internalForces()'s values (its other rows are unspecified);
  /// costs those rows of K v instead of a product while internalForces() is not yet computed.
  const Eigen::VectorXd& internalForcesAt(const std::vector<int>& nodes);
  /// Elastic forces f(x) at the start of the last step, 3n, N.
  const Eigen::VectorXd& elasticForces() const { return elastic_forces_; }

  const SolverSettings& settings() const { return settings_; }
  /// Takes effect at the next step (linear solver, tolerance...); the caller validates.
  void setSettings(const SolverSettings& settings) { settings_ = settings; }
  /// Live material edit between steps (FemBody::setMaterial): `model` has the same mesh. The
  /// state's warm starts stay; internalForces() keeps reporting the last step as it was taken
  /// (with the material it was taken with) until the next step.
  void replaceModel(std::shared_ptr<const FemModel> model);
  const FemModel& model() const { return *model_; }
  const SystemOperator& system() const { return system_; }

  /// What the next step and the force queries remember of the last step besides the FemState:
  /// the CG's warm start and the end-of-step internal forces (checkpoints, FemBody::checkpoint).
  struct Memory {
    Eigen::VectorXd previous_velocities, velocity_next, elastic_forces, internal_forces;
    double last_dt = 0;
  };
  Memory memory();
  /// Back to a remembered step: the next step continues bit for bit as it did after memory().
  void restore(const Memory& memory);

  /// Stages 1-2 alone: rotations and elastic forces at `state`; returns the elastic energy, J
  /// (also used by tests).
  double computeElasticForces(FemState& state);

 private:
  // Stage 2's pressure pass for nodal pressure (adds to element_forces_); the volumetric energy.
  double addNodalPressureForces();
  // Stage 2's volume barrier (fem/volume_barrier.h): adds its forces to elastic_forces_ and its
  // stiffness to K for the tets of mesh() below the threshold; returns its energy, J.
  double addVolumeBarrier(const FemState& state);
  // Stages 1-2 of a hyperelastic body: energy, forces and element stiffnesses at `state`
  // (src/solve/implicit_stepper_newton.cpp, as are the functions below up to the next comment).
  double computeHyperelasticForces(FemState& state);
  // Stage 4 of a hyperelastic body: the Newton solve, v' into velocity_next_.
  LinearSolveReport solveNewton();
  // Whether the warm start's prediction puts the prescribed nodes near their targets (the first
  // Newton iterate then starts from it).
  bool predictionFits() const;
  // A linear solve by settings_.linear_solver of A v = b under `constraints` (CG to relative
  // `tolerance`; CHOLMOD exact).
  LinearSolveReport linearSolve(const NodeConstraints& constraints, const Eigen::VectorXd& b,
                                Eigen::VectorXd& v, double tolerance);
  // The pass at x_n + dt v (into trial_) with the stiffnesses `stiffness` asks for, then
  // iterateResidual: returns Phi(v).
  double evaluateIterate(const Eigen::VectorXd& v, TetStiffnessKind stiffness);
  // From the pass's forces at v and its elastic `energy`: iterate_forces_, lagged_product_
  // (K_0 v) and newton_residual_ = r(v); returns Phi(v).
  double iterateResidual(const Eigen::VectorXd& v, double energy);
  // Phi at v from the elastic energy there and the step's quadratic terms.
  double incrementalPotential(const Eigen::VectorXd& v, double elastic_energy,
                              const Eigen::VectorXd& lagged_v) const;
  // A Newton direction dv at the last evaluated iterate: S r solved with the exact Hessian, or the
  // projected one where that is not positive definite, as accurately as a Newton residual of
  // `target` needs; its relative residual reported against the step's residual `scale`.
  LinearSolveReport newtonDirection(const Eigen::VectorXd& free_residual, double target,
                                    double scale, Eigen::VectorXd& dv);
  // Backtracks along dv from v (Phi(v) = phi); on success v and phi move to the accepted point.
  bool lineSearch(Eigen::VectorXd& v, const Eigen::VectorXd& dv, double& phi);
  // Stage 6's verdict on the Newton solve, into report.
  void judgeNewton(StepReport& report) const;
  // Stage 3: rhs_. False (and report's health and message set) when b is not finite.
  bool buildRightHandSide(const FemState& state, const Eigen::VectorXd& external_forces, double dt,
                          StepReport& report);
  // Stage 4's system: A's coefficients for dt; velocity_next_ = the warm start, extrapolated from
  // the last two steps' velocities.
  void prepareSystem(const FemState& state, double dt);
  // Stage 5: v = v', x += dt v'.
  void integratePositions(FemState& state, double dt) const;
  // Stage 6: kinetic energy, top speed and the step's health, into report.
  void checkHealth(const FemState& state, StepReport& report) const;

  std::shared_ptr<const FemModel> model_;
  SolverSettings settings_;
  const Parallel& parallel_;
  SystemOperator system_;
  ProjectedCg cg_;
  std::unique_ptr<CholmodSolver> cholmod_;
  const NodeConstraints* constraints_ = nullptr;  // the prepared step's (the caller's)

  Eigen::VectorXd elastic_forces_, rhs_, velocity_next_, internal_forces_, scratch_;
  Eigen::VectorXd node_forces_, node_scratch_;   // internalForcesAt()'s rows
  Eigen::VectorXd previous_velocities_;          // v of the step before, for the CG warm start
  std::vector<Eigen::Vector3d> element_forces_;  // N per element (SystemOperator::gather)
  std::vector<double> element_energy_;
  // Nodal pressure (fem/nodal_pressure.h): per-tet volumetric strain, then pressure; per-node
  // averaged strain.
  std::vector<double> tet_strain_, node_strain_;
  // Per tet: 1 where the batched force pass saw det F <= 0 and the SVD path redid it.
  std::vector<unsigned char> needs_svd_;
  // Per tet of mesh(): J = det F this step (volume barrier); how many are below its threshold.
  std::vector<double> volume_ratio_;
  int barrier_tets_ = 0;
  // Hyperelastic bodies: the element pass; the step's start (x_n, v_n), external forces and
  // homogeneous constraints; the stiffness at the start (for beta); the iterate's forces, residual
  // and K_n v; the Newton report of the last solve.
  std::unique_ptr<HyperelasticPass> hyperelastic_;
  Eigen::VectorXd start_positions_, start_velocities_, step_external_forces_;
  NodeConstraints newton_constraints_;
  std::vector<Eigen::Matrix3d> start_stiffness_;
  // The pass's evaluations() when iterate_forces_ was gathered; the constrained nodes of the
  // Newton residual's scale (their rows of A v_prescribed).
  long gathered_evaluation_ = -1;
  std::vector<int> constrained_nodes_;
  Eigen::VectorXd iterate_forces_, newton_residual_, lagged_product_, trial_;
  NewtonReport newton_;
  // linearizeAboutFreeMotion(): the prepared system is the linearisation about free_velocity_.
  bool linearized_ = false;
  Eigen::VectorXd free_velocity_;
  bool internal_forces_valid_ = false;
  double last_dt_;  // s, dt of the last step (the internal forces' linearisation uses it)
};

}  // namespace torsion
