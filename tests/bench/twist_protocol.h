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
  double max_speed = 0;              ///< largest node speed seen at the end of any step, m/s
  double driven_error = 0;           ///< max |x - target| of driven nodes at the end, m
  long setup_rss_kb = 0;             ///< peak RSS before the first step
  long peak_rss_kb = 0;              ///< peak RSS at the end
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
};
TwistResult runBulletTwist(const TwistProtocol& protocol, const TetMesh& mesh,
                           const BulletOptions& options);

}  // namespace torsion::bench
