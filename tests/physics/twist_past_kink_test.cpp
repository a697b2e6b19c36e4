// A bar twisted past its kink (docs/validation-twist.md, "Twisting past the kink"). A bar clamped
// at both ends and twisted at fixed length buckles into a loop once the twist passes a few pi
// (Greenhill: at a twist moment of about 2.9 pi EI / L, i.e. a twist angle of about
// 2.9 pi EI / GJ = 3.7 pi for a round bar at nu = 0.3). In the plain corotated material (no volume
// barrier) the kink's crease then flattens its tets through zero volume and the loop passes
// through the bar: tets invert and the stored twist escapes as motion. The step anomaly monitor
// must say so; at 2 pi it must stay quiet. With the volume barrier (fem/volume_barrier.h, the
// default) no tet inverts; without self-contact the loop still passes through the bar at 5 pi
// (flagged as a release), and with self-contact the bar keeps its 4 pi: no surface crossing
// deeper than the contact's gap tolerance (the exact checker), no anomaly, the stored energy and
// the hand's torque held. The 2430-tet cylinder of the twist scenes (r = 1, L = 10), twisted five
// times faster than they do so that the test takes seconds.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "../bench/crossing_kinds.h"
#include "torsion/analysis/step_anomalies.h"
#include "torsion/analysis/surface_intersections.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion {
namespace twist_past_kink_test {

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
  double end_elastic = 0;   ///< J, the last step's
  double peak_torque = 0;   ///< N m, the hand's torque about the axis
  double end_torque = 0;    ///< N m
  int max_inverted = 0;     ///< inverted tets, the most in any step
  int checked_steps = 0;    ///< steps the exact checker ran after
  int crossing_steps = 0;   ///< of which with crossing surface triangles
  int deep_steps = 0;       ///< of which with a pair deeper than the gap tolerance
  double deepest = 0;       ///< m, the deepest crossing pair
  int contact_steps = 0;    ///< steps that ended with an active self-contact
  int max_active = 0;       ///< active self-contacts, the most in any step
  int unconverged = 0;      ///< steps whose self-contact solve stopped unconverged
};

struct TwistOptions {
  double max_angle = 4 * M_PI;  ///< rad, then held
  int hold_steps = 300;
  Material material;  ///< E = 1e5 Pa, nu = 0.3, rho = 1000 kg/m^3, beta = 0.01 s: the scenes'
  bool self_contact = false;
  int check_from = -1;  ///< run the exact crossing checker after every step from this one on
};

/// Twists the bar's top face about the axis at kRate up to `max_angle` and holds it there for
/// `hold_steps` steps, feeding the anomaly monitor after every step.
TwistRun twist(const TwistOptions& options) {
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
  FemBody* body = world.addBody("bar", mesh, options.material).value();
  if (options.self_contact) {
    SelfContactSettings contact;
    contact.friction = 0.3;
    EXPECT_TRUE(body->enableSelfContact(contact).ok());
  }
  std::vector<int> base, top;
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    const double z = mesh.restPositions()[static_cast<size_t>(n)].z();
    if (z < 1e-9) base.push_back(n);
    if (z > kLength - 1e-9) top.push_back(n);
  }
  body->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0);
  const double max_angle = options.max_angle;
  const int hand = body->carryNodes(
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
  const int steps = static_cast<int>(std::ceil(max_angle / kRate / kDt)) + options.hold_steps;
  for (int k = 1; k <= steps; ++k) {
    const WorldStepReport report = world.step();
    if (!report.ok) {
      run.stable = false;
      break;
    }
    run.steps = k;
    const StepReport& r = body->lastReport();
    const StepObservation observation = observeStep(body->model(), body->state().positions, r);
    monitor.observe(k, observation);
    run.max_inverted = std::max(run.max_inverted, observation.inverted_elements);
    run.peak_elastic = std::max(run.peak_elastic, r.elastic_energy);
    run.peak_kinetic = std::max(run.peak_kinetic, r.kinetic_energy);
    run.peak_speed = std::max(run.peak_speed, r.max_speed);
    run.end_elastic = r.elastic_energy;
    run.end_torque = std::abs(body->groupWrench(hand, Eigen::Vector3d(0, 0, kLength)).torque.z());
    run.peak_torque = std::max(run.peak_torque, run.end_torque);
    if (const SelfContactSolver* contact = body->selfContact(); contact != nullptr) {
      run.contact_steps += contact->stats().active > 0 ? 1 : 0;
      run.max_active = std::max(run.max_active, contact->stats().active);
      run.unconverged += contact->stats().converged ? 0 : 1;
    }
    if (options.check_from < 0 || k < options.check_from) continue;
    ++run.checked_steps;
    const std::vector<TrianglePair> pairs =
        findSurfaceIntersections(mesh.surfaceTriangles(), body->state().positions);
    if (pairs.empty()) continue;
    ++run.crossing_steps;
    const SelfContactSolver* contact = body->selfContact();
    const CrossingKinds kinds =
        classifyCrossings(pairs, mesh.surfaceTriangles(), body->state().positions,
                          contact != nullptr ? contact->contacts() : std::vector<SurfaceContact>{},
                          contact != nullptr ? contact->settings().max_depth : 0.25,
                          contact != nullptr ? contact->gapTolerance() : 0.0);
    if (kinds.within_tolerance < static_cast<int>(pairs.size())) ++run.deep_steps;
    run.deepest = std::max(run.deepest, kinds.deepest);
  }
  run.anomalies = monitor.anomalies();
  return run;
}

TwistRun twist(double max_angle, int hold_steps) {
  TwistOptions options;
  options.max_angle = max_angle;
  options.hold_steps = hold_steps;
  return twist(options);
}

void print(const TwistRun& run) {
  std::printf(
      "peak elastic %g J (end %g J), kinetic %g J, node speed %g m/s; hand torque peak %g N m, "
      "end %g N m; inverted tets at most %d; crossings in %d of %d checked steps (%d deeper than "
      "the gap tolerance), deepest %g m; self-contact active in %d steps (at most %d), %d "
      "unconverged\n",
      run.peak_elastic, run.end_elastic, run.peak_kinetic, run.peak_speed, run.peak_torque,
      run.end_torque, run.max_inverted, run.crossing_steps, run.checked_steps, run.deep_steps,
      run.deepest, run.contact_steps, run.max_active, run.unconverged);
  for (const Anomaly& a : run.anomalies)
    std::printf("%s at steps %d-%d, peak %g\n", toString(a.kind), a.first_step, a.last_step,
                a.peak);
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
  // The plain corotated material: its crease inverts (the monitor's inverted-tet check is what
  // this exercises).
  TwistOptions options;
  options.max_angle = 5 * M_PI;
  options.material.barrier_threshold = 0;
  const TwistRun run = twist(options);
  ASSERT_TRUE(run.stable);
  print(run);
  // Nothing before the twist nears the kink: the first anomaly is past 3 pi.
  ASSERT_FALSE(run.anomalies.empty());
  EXPECT_GT(run.anomalies.front().first_step * kDt * kRate, 3 * M_PI);
  EXPECT_TRUE(has(run, AnomalyKind::kInvertedElements));
  EXPECT_TRUE(has(run, AnomalyKind::kEnergyRelease));
}

TEST(TwistPastKink, WithTheVolumeBarrierNoTetInvertsAndWithoutSelfContactTheReleaseIsFlagged) {
  // The default material: the barrier keeps every tet's volume positive, but nothing keeps the
  // loop out of the bar, which it passes through near 4.5 pi.
  TwistOptions options;
  options.max_angle = 5 * M_PI;
  const TwistRun run = twist(options);
  ASSERT_TRUE(run.stable);
  print(run);
  EXPECT_EQ(run.max_inverted, 0);
  EXPECT_FALSE(has(run, AnomalyKind::kInvertedElements));
  ASSERT_TRUE(has(run, AnomalyKind::kEnergyRelease));
  EXPECT_GT(run.anomalies.front().first_step * kDt * kRate, 4 * M_PI);
  EXPECT_LT(run.end_elastic, 0.5 * run.peak_elastic);  // most of the twist is gone
}

TEST(TwistPastKink, WithSelfContactTheBarKeepsItsFourPi) {
  // The scene of bench_kink_self_contact: 4 pi at 0.5 rad/s, held 15 s, self-contact on
  // (friction 0.3). The exact checker runs after every step from 3.2 pi (step 2000) on, before
  // the kink forms (the hand's torque peaks near 3.7 pi at this rate). The long hold lets the
  // kink's loop come down onto the bar (from about 8 s into the hold), so self-contact, not only
  // the volume barrier, holds the twist.
  TwistOptions options;
  options.self_contact = true;
  options.check_from = 2000;
  options.hold_steps = 1500;
  const TwistRun run = twist(options);
  ASSERT_TRUE(run.stable);
  print(run);
  // The bar kinked: the hand's torque fell from its peak (buckling) ...
  EXPECT_LT(run.end_torque, 0.97 * run.peak_torque);
  // ... but kept its twist through the hold: the unwound bar (no barrier, or no self-contact)
  // ends with 33 % of the peak elastic energy and 39 % of the peak torque; measured 98.7 % and
  // 82.5 % after the 15 s hold here.
  EXPECT_GT(run.end_elastic, 0.9 * run.peak_elastic);
  EXPECT_GT(run.end_torque, 0.75 * run.peak_torque);
  EXPECT_EQ(run.max_inverted, 0);
  EXPECT_TRUE(run.anomalies.empty());  // no inverted tets, no release, no speed burst
  EXPECT_EQ(run.deep_steps, 0) << "deepest crossing " << run.deepest << " m";
  // The loop pressed on the bar and was held there, every contact solve converged, and with the
  // contact thickness no two surface triangles touched at any checked step.
  EXPECT_GE(run.contact_steps, 100);
  EXPECT_GE(run.max_active, 5);
  EXPECT_EQ(run.unconverged, 0);
  EXPECT_EQ(run.crossing_steps, 0) << "deepest crossing " << run.deepest << " m";
}

}  // namespace twist_past_kink_test
}  // namespace torsion
