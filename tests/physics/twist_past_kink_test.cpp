// A bar twisted past its kink (docs/validation.md, "Twisting past the kink"). A bar clamped at
// both ends and twisted at fixed length buckles into a loop once the twist passes a few pi
// (Greenhill: at a twist moment of about 2.9 pi EI / L, i.e. a twist angle of about
// 2.9 pi EI / GJ = 3.7 pi for a round bar at nu = 0.3). Without self-contact the loop then passes
// through the bar and the stored twist escapes as motion: tets invert and elastic energy turns
// into kinetic energy within a fraction of a second. The step anomaly monitor must say so; at
// 2 pi it must stay quiet. The 2430-tet cylinder of the twist scenes (r = 1, L = 10), twisted
// five times faster than they do so that the test takes seconds.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "torsion/analysis/step_anomalies.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion {
namespace {

constexpr double kLength = 10.0;  // m
constexpr double kRate = 0.5;     // rad/s of twist (the scenes: 0.1)
constexpr double kDt = 0.01;      // s

struct TwistRun {
  std::vector<Anomaly> anomalies;
  int steps = 0;
  bool stable = true;
  double peak_elastic = 0;  ///< J
  double peak_kinetic = 0;  ///< J
  double peak_speed = 0;    ///< m/s
};

/// Twists the bar's top face about the axis at kRate up to `max_angle` and holds it there for
/// `hold_steps` steps, feeding the anomaly monitor after every step.
TwistRun twist(double max_angle, int hold_steps) {
  // The 2 pi run checks the quiet side; the 5 pi run passes the kink (near 3.6 pi at 0.1 rad/s).
  Result<LoadedMesh> loaded = readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_2430.node");
  if (!loaded.ok()) {
    ADD_FAILURE() << loaded.error().message;
    return {};
  }
  const TetMesh& mesh = loaded.value().mesh;
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = kDt;
  FemWorld world(settings);
  Material material;  // E = 1e5 Pa, nu = 0.3, rho = 1000 kg/m^3, beta = 0.01 s: the scenes'
  FemBody* body = world.addBody("bar", mesh, material).value();
  std::vector<int> base, top;
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    const double z = mesh.restPositions()[static_cast<size_t>(n)].z();
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
    const StepReport& r = body->lastReport();
    monitor.observe(k, observeStep(body->model(), body->state().positions, r));
    run.peak_elastic = std::max(run.peak_elastic, r.elastic_energy);
    run.peak_kinetic = std::max(run.peak_kinetic, r.kinetic_energy);
    run.peak_speed = std::max(run.peak_speed, r.max_speed);
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
  const TwistRun run = twist(5 * M_PI, 300);
  ASSERT_TRUE(run.stable);
  std::printf("peak elastic %g J, kinetic %g J, node speed %g m/s\n", run.peak_elastic,
              run.peak_kinetic, run.peak_speed);
  for (const Anomaly& a : run.anomalies)
    std::printf("%s at steps %d-%d, peak %g\n", toString(a.kind), a.first_step, a.last_step,
                a.peak);
  // Nothing before the twist nears the kink: the first anomaly is past 3 pi.
  ASSERT_FALSE(run.anomalies.empty());
  EXPECT_GT(run.anomalies.front().first_step * kDt * kRate, 3 * M_PI);
  EXPECT_TRUE(has(run, AnomalyKind::kInvertedElements));
  EXPECT_TRUE(has(run, AnomalyKind::kEnergyRelease));
}

}  // namespace
}  // namespace torsion
