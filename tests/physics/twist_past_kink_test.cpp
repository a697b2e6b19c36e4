// A slender bar twisted past its kink (docs/validation.md, "Twisting past the kink"). A bar clamped
// at both ends and twisted at fixed length buckles into a loop once the twist passes a few pi
// (Greenhill: twist moment ~ 2.9 pi EI / L, i.e. a twist angle of about 2.9 pi EI / GJ, 4.4 pi for
// a square section at nu = 0.3). Without self-contact the loop then passes through the bar and
// the stored twist escapes as motion: tets invert and elastic energy turns into kinetic energy in
// a fraction of a second. The step anomaly monitor must say so; below the kink it must stay quiet.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "torsion/analysis/step_anomalies.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

constexpr double kSide = 0.2;    // m, square section
constexpr double kLength = 4.0;  // m: slenderness 20
constexpr double kRate = 1.0;    // rad/s of twist
constexpr double kDt = 0.01;     // s

struct TwistRun {
  std::vector<Anomaly> anomalies;
  int steps = 0;
  bool stable = true;
  double final_angle = 0;
};

/// Twists the bar's top face about the axis at kRate up to `max_angle` and holds it there for
/// `hold_steps` steps, feeding the anomaly monitor after every step.
TwistRun twist(double max_angle, int hold_steps) {
  Result<TetMesh> mesh = makeBoxTetMesh(Eigen::Vector3d(-kSide / 2, -kSide / 2, 0),
                                        Eigen::Vector3d(kSide / 2, kSide / 2, kLength), 2, 2, 40);
  EXPECT_TRUE(mesh.ok());
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = kDt;
  FemWorld world(settings);
  Material material;
  material.youngs_modulus = 1e6;  // Pa; rho = 1000 kg/m^3, nu = 0.3, beta = 0.01 s (defaults)
  FemBody* body = world.addBody("bar", mesh.value(), material).value();
  std::vector<int> base, top;
  for (int n = 0; n < mesh.value().nodeCount(); ++n) {
    const double z = mesh.value().restPositions()[static_cast<size_t>(n)].z();
    if (z < 1e-9) base.push_back(n);
    if (z > kLength - 1e-9) top.push_back(n);
  }
  body->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0);
  body->carryNodes(
      "top", top,
      [max_angle](double t) {
        Frame f;
        f.origin = Eigen::Vector3d(0, 0, kLength);
        f.rotation = Eigen::AngleAxisd(std::min(kRate * t, max_angle), Eigen::Vector3d::UnitZ());
        return f;
      },
      0);

  StepAnomalyMonitor monitor;
  TwistRun run;
  const int steps = static_cast<int>(std::ceil(max_angle / kRate / kDt)) + hold_steps;
  for (int k = 1; k <= steps; ++k) {
    const WorldStepReport report = world.step();
    if (!report.ok) {
      run.stable = false;
      break;
    }
    run.steps = k;
    monitor.observe(k, observeStep(body->model(), body->state().positions, body->lastReport()));
  }
  run.anomalies = monitor.anomalies();
  return run;
}

bool has(const TwistRun& run, AnomalyKind kind) {
  for (const Anomaly& a : run.anomalies)
    if (a.kind == kind) return true;
  return false;
}

TEST(TwistPastKink, BelowTheKinkNothingIsFlagged) {
  const TwistRun run = twist(2 * M_PI, 100);
  ASSERT_TRUE(run.stable);
  for (const Anomaly& a : run.anomalies)
    ADD_FAILURE() << toString(a.kind) << " at steps " << a.first_step << "-" << a.last_step
                  << ", peak " << a.peak;
}

TEST(TwistPastKink, WellPastTheKinkInvertedTetsAndReleasedEnergyAreFlagged) {
  const TwistRun run = twist(8 * M_PI, 300);
  for (const Anomaly& a : run.anomalies)
    std::printf("%s at steps %d-%d, peak %g\n", toString(a.kind), a.first_step, a.last_step,
                a.peak);
  EXPECT_TRUE(has(run, AnomalyKind::kInvertedElements));
  EXPECT_TRUE(has(run, AnomalyKind::kEnergyRelease));
}

}  // namespace
}  // namespace torsion
