#pragma once
// The cylinder-twist benchmark protocol, shared by our solver's runner and Bullet's, so both run
// exactly the same scene: a cylinder along +z from z = 0 to z = L (axis x = y = 0), no gravity,
// nodes with rest z < 1e-6 fixed, nodes with rest z > L - 1e-6 turned about the z axis by
//   angle(t) = final_angle * min(t / (ramp_steps dt), 1),
// total_steps steps of dt. At the end, the twist angle of thin slices at z = L/4, L/2, 3L/4
// (rest positions, Procrustes fit, torsion::twistProfile) is compared with St-Venant's linear
// profile angle(z) = final_angle z / L.
//
// Nothing here includes Bullet: bullet_twist_runner.cpp is the only file that does.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "torsion/mesh/tet_mesh.h"
#include "torsion/solve/solver_settings.h"

namespace torsion::bench {

struct TwistProtocol {
  double youngs_modulus = 1e5;  ///< E, Pa
  double poisson_ratio = 0.3;   ///< nu
  double density = 1000;        ///< rho, kg/m^3
  double time_step = 0.01;      ///< dt, s (one benchmark "step"; explicit substeps divide it)
  int ramp_steps = 300;         ///< steps to reach final_angle
  int total_steps = 600;        ///< ramp + hold
  double final_angle = 1.5707963267948966;  ///< pi/2, rad
  /// > 0: the driven end oscillates instead, angle(t) = final_angle sin(2 pi f t) (a fast hand:
  /// final_angle = pi/4, f = 2 Hz); Hz. The end-of-run twist profile then means nothing.
  double oscillation_hz = 0;
  /// Rayleigh stiffness damping beta, s (C = beta K). Ours: Material::stiffness_damping; Bullet's
  /// btDeformableLinearElasticityForce: damping_beta (same meaning, see bullet_twist_runner.cpp).
  double stiffness_damping = 0.01;
  /// The constitutive law on both sides (same E, nu, rho, beta): kCorotated is ours corotated
  /// against Bullet's btDeformableLinearElasticityForce (implicit) or btDeformableCorotatedForce
  /// (explicit); kNeoHookean is our stable neo-Hookean (Material::law, Newton step) against
  /// Bullet's btDeformableNeoHookeanForce (bullet_twist_runner.cpp: parameters and damping).
  enum class Law { kCorotated, kNeoHookean } law = Law::kCorotated;
  /// Record the end torque after every step (TwistResult::curve), outside the timed region.
  bool record_curve = false;
  double max_speed = 100;             ///< m/s: a faster node means the run is unstable
  double slice_half_thickness = 0.3;  ///< m, half thickness of the measuring slices
  std::vector<double> slice_fractions{0.25, 0.5, 0.75};  ///< slice z / L

  /// Prescribed angle of the driven end at time t, rad.
  double angle(double t) const;
};

enum class NodeRole : std::uint8_t { kFree, kFixed, kDriven };

/// Which nodes are held, which are turned, and the cylinder's extent.
struct TwistScene {
  std::vector<NodeRole> roles;
  double z_min = 0, z_max = 0;  ///< rest bounds along z; L = z_max (the protocol's z = 0 end)
  int fixed = 0, driven = 0;
  double length() const { return z_max; }
};
TwistScene classifyNodes(const TetMesh& mesh);

/// Torque about the z axis that the driver applies to the body through the driven nodes, N m:
/// -sum_i (x_i x f_i)_z over `driven`, f_i the force the body's elements (elastic + damping) exert
/// on node i (3n vectors; only the driven rows are read). Positive turns the body the way the
/// protocol turns it.
double drivenTorqueZ(const Eigen::VectorXd& positions, const Eigen::VectorXd& internal_forces,
                     const std::vector<int>& driven);

/// St-Venant's torque for the protocol's end angle on a circular section of radius `radius`:
/// mu (pi radius^4 / 2) angle / L (linear elasticity; tet4 meshes are stiffer), N m.
double stVenantTorque(const TwistProtocol& protocol, double radius, double length, double angle);

/// Rest position turned about the z axis (through x = y = 0) by `angle`.
Eigen::Vector3d turnedAboutZ(const Eigen::Vector3d& rest, double angle);

enum class RunStatus { kOk, kNonFinite, kBlowUp, kSolverFailed, kSetupFailed };
const char* toString(RunStatus status);

/// Everything one configuration reports. Times are wall clock of the stepping loop only (setup,
/// health checks of the harness and the final measurement are outside).
struct TwistResult {
  RunStatus status = RunStatus::kOk;
  std::string message;
  int steps_done = 0;
  double setup_seconds = 0;
  std::vector<double> step_ms;       ///< wall clock per benchmark step (all substeps of one dt)
  double loop_cpu_seconds = 0;       ///< process CPU time (all threads) of the stepping loop
  std::vector<int> step_iterations;  ///< linear-solver iterations per step (sum over substeps)
  int not_converged_steps = 0;       ///< steps whose solver stopped above tolerance (ours)
  /// Newton iterations (linear solves) per step: ours with a hyperelastic law
  /// (StepReport::newton.iterations); Bullet implicit: its solves per step (a fixed count, see
  /// BulletOptions::newton_iterations). Empty otherwise.
  std::vector<int> step_newton;
  int newton_not_converged_steps = 0;  ///< ours: steps whose Newton solve missed its tolerance
  long line_search_cuts = 0;           ///< ours: Newton step halvings over the run
  long projected_iterations = 0;       ///< ours: Newton directions with the projected Hessian
  /// Torque about z the driver applies at the end of the last step (drivenTorqueZ), N m; NaN
  /// where not measured (Bullet explicit).
  double end_torque = std::numeric_limits<double>::quiet_NaN();
  struct CurvePoint {
    int step = 0;       ///< 1-based: the state at the end of this step
    double angle = 0;   ///< prescribed angle of the driven end, rad
    double torque = 0;  ///< drivenTorqueZ, N m
  };
  std::vector<CurvePoint> curve;  ///< every step, when TwistProtocol::record_curve
  double max_speed = 0;           ///< largest node speed seen at the end of any step, m/s
  double driven_error = 0;        ///< max |x - target| of driven nodes at the end, m
  long setup_rss_kb = 0;          ///< peak RSS before the first step
  long peak_rss_kb = 0;           ///< peak RSS at the end
  // Final twist profile
  std::vector<double> slice_z, slice_angle, slice_expected, slice_error;
  std::vector<int> slice_nodes;
  double tip_angle = 0;             ///< angle of the driven end, rad
  Eigen::VectorXd final_positions;  ///< 3n
  std::string solver_detail;        ///< e.g. "cg block-jacobi tol 1e-4"
};

/// Fills slice_* of `result` from final positions (3n) against the rest mesh.
void measureTwist(const TwistProtocol& protocol, const TetMesh& mesh, const TwistScene& scene,
                  const Eigen::VectorXd& positions, TwistResult& result);

/// Peak resident set size of this process so far, kB (getrusage ru_maxrss).
long peakRssKb();
/// CPU time of this process (all threads) so far, s. Less sensitive than wall clock to other
/// processes competing for the cores (it still sees their cache and memory-bandwidth pressure).
double processCpuSeconds();

/// q-quantile (0..1) of `values`, linear interpolation between order statistics; NaN if empty.
double quantile(std::vector<double> values, double q);

// ---- the two sides ----

struct TorsionOptions {
  bool cholmod = false;
  double tolerance = 1e-4;  ///< CG relative residual
  int threads = 1;
  bool tet10 = false;  ///< quadratic elements on the mesh (all P2 nodes take part in the protocol)
  PreconditionerKind preconditioner = PreconditionerKind::kBlockJacobi;
  int refactor_interval = SolverSettings{}.refactor_interval;
  int refactor_iterations = SolverSettings{}.refactor_iterations;
  double newton_tolerance = SolverSettings{}.newton_tolerance;  ///< hyperelastic laws only
};
TwistResult runTorsionTwist(const TwistProtocol& protocol, std::shared_ptr<const TetMesh> mesh,
                            const TorsionOptions& options);

struct BulletOptions {
  bool implicit = true;
  /// btConjugateGradient tolerance: CG stops when r.z < tolerance * min(1, z0.b0) (b0 the
  /// right-hand side, z = preconditioned residual). <= 0: Bullet's default (SIMD_EPSILON).
  double cg_tolerance = -1;
  int cg_max_iterations = 300;       ///< Bullet's default (kMaxConjugateGradientIterations)
  bool mass_preconditioner = false;  ///< initialise the mass preconditioner (memo section 3)
  int substeps = 1;                  ///< explicit: stepSimulation calls of dt / substeps per step
  /// Implicit: btDeformableBodySolver::m_maxNewtonIterations (Bullet's default 1). Its stop test
  /// (absolute residual norm < 1e-4, the unprojected forces on held nodes included) never fires
  /// in this scene, so every step takes exactly this many linearised solves.
  int newton_iterations = 1;
};
TwistResult runBulletTwist(const TwistProtocol& protocol, const TetMesh& mesh,
                           const BulletOptions& options);

}  // namespace torsion::bench
