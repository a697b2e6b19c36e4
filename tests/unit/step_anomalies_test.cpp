// The step anomaly monitor (analysis/step_anomalies.h) on hand-made sequences: a tet turned
// inside out, stored energy released into motion, a speed burst; and no alarm where energy only
// changes hands (a rebound, a fall) or the body is driven steadily.
#include "torsion/analysis/step_anomalies.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <memory>

#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

StepObservation observation(double kinetic, double elastic, double speed = 0.1) {
  StepObservation o;
  o.kinetic_energy = kinetic;
  o.elastic_energy = elastic;
  o.max_speed = speed;
  return o;
}

TEST(StepAnomalies, CountsATetTurnedInsideOutByHand) {
  Result<TetMesh> mesh = makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 1, 1, 1);
  ASSERT_TRUE(mesh.ok());
  auto model = FemModel::create(std::make_shared<const TetMesh>(mesh.value()), Material{});
  ASSERT_TRUE(model.ok());
  Eigen::VectorXd x(3 * mesh.value().nodeCount());
  for (int n = 0; n < mesh.value().nodeCount(); ++n)
    x.segment<3>(3 * n) = mesh.value().restPositions()[static_cast<size_t>(n)];
  StepReport report;
  EXPECT_EQ(observeStep(*model.value(), x, report).inverted_elements, 0);

  // Push the first tet's corner 0 through its opposite face: that tet (at least) inverts.
  const auto& tet = mesh.value().tets()[0];
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int k = 1; k < 4; ++k)
    centroid += x.segment<3>(3 * tet[static_cast<size_t>(k)]) / 3;
  x.segment<3>(3 * tet[0]) += 2 * (centroid - x.segment<3>(3 * tet[0]));
  const int inverted = observeStep(*model.value(), x, report).inverted_elements;
  EXPECT_GE(inverted, 1);

  StepAnomalyMonitor monitor;
  StepObservation o = observation(0, 1);
  EXPECT_TRUE(monitor.observe(1, o).empty());
  o.inverted_elements = inverted;
  const std::vector<AnomalyKind> started = monitor.observe(2, o);
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0], AnomalyKind::kInvertedElements);
  EXPECT_TRUE(monitor.observe(3, o).empty());  // still inverted: the same range, no new warning
  ASSERT_EQ(monitor.anomalies().size(), 1u);
  EXPECT_EQ(monitor.anomalies()[0].first_step, 2);
  EXPECT_EQ(monitor.anomalies()[0].last_step, 3);
  EXPECT_EQ(monitor.anomalies()[0].peak, inverted);
}

TEST(StepAnomalies, FlagsStoredElasticEnergyReleasedAsMotion) {
  StepAnomalyMonitor monitor;
  int step = 0;
  // A slow twist: elastic energy builds up to 1000 J and is held; kinetic energy stays tiny.
  for (; step < 400; ++step)
    EXPECT_TRUE(
        monitor.observe(step, observation(1e-3, 1000.0 * std::min(step, 300) / 300)).empty());
  // The kink: in 20 steps half the stored energy turns into motion.
  std::vector<int> release_steps;
  for (int k = 1; k <= 20; ++k, ++step) {
    for (AnomalyKind kind : monitor.observe(step, observation(25.0 * k, 1000 - 25.0 * k)))
      if (kind == AnomalyKind::kEnergyRelease) release_steps.push_back(step);
  }
  ASSERT_EQ(release_steps.size(), 1u);
  // 10 % of the 1000 J held is passed at the 5th step of the release (125 J; the 4th has 100 J).
  EXPECT_EQ(release_steps[0], 404);
  const Anomaly& a = monitor.anomalies().back();
  EXPECT_EQ(a.kind, AnomalyKind::kEnergyRelease);
  EXPECT_NEAR(a.peak, 0.5, 0.01);  // 500 J gained over ~1000 J stored
}

TEST(StepAnomalies, NoAlarmWhenARebounceGivesBackWhatTheImpactTook) {
  StepAnomalyMonitor monitor;
  int step = 0;
  // Falling: kinetic energy grows, no elastic energy (no release: nothing stored fell).
  for (; step < 50; ++step)
    EXPECT_TRUE(monitor.observe(step, observation(0.5 * step, 0, 0.1 * step)).empty()) << step;
  // Impact: kinetic into elastic over 5 steps, then back out with 20 % lost.
  for (int k = 1; k <= 5; ++k, ++step)
    EXPECT_TRUE(monitor.observe(step, observation(25 - 5.0 * k, 5.0 * k, 5 - k)).empty());
  for (int k = 1; k <= 5; ++k, ++step)
    EXPECT_TRUE(monitor.observe(step, observation(4.0 * k, 25 - 5.0 * k, 0.8 * k)).empty());
  EXPECT_TRUE(monitor.anomalies().empty());
}

TEST(StepAnomalies, NoReleaseWhenAnImpactStoresEnergyAndGivesItBackWithinAFewSteps) {
  // A body at rest struck by a rigid one: the blow is stored as elastic energy over 5 steps and
  // comes back out as the body's motion over the next 5, more kinetic energy than it ever had.
  StepAnomalyMonitor monitor;
  int step = 0;
  for (; step < 100; ++step)
    EXPECT_TRUE(monitor.observe(step, observation(0, 0, 0)).empty());
  for (int k = 1; k <= 5; ++k, ++step)
    EXPECT_TRUE(monitor.observe(step, observation(0, 20.0 * k, 0)).empty());
  for (int k = 1; k <= 5; ++k, ++step)
    EXPECT_TRUE(monitor.observe(step, observation(15.0 * k, 100 - 20.0 * k, 0.1)).empty()) << k;
}

TEST(StepAnomalies, NoReleaseWhenMotionIsNotPaidByElasticEnergy) {
  // Kinetic energy rising while the elastic store grows too (work done on the body by a hand).
  StepAnomalyMonitor monitor;
  for (int step = 0; step < 100; ++step)
    EXPECT_TRUE(monitor.observe(step, observation(2.0 * step, 100.0 + step)).empty());
}

TEST(StepAnomalies, FlagsASpeedBurstOverTheEarlierMedianOnly) {
  StepAnomalyMonitor monitor;
  int step = 0;
  for (; step < 160; ++step)
    monitor.observe(step, observation(0, 0, 0.5 + 0.01 * (step % 7)));
  // Four times the median: fast, but no burst.
  EXPECT_TRUE(monitor.observe(step++, observation(0, 0, 2.0)).empty());
  const std::vector<AnomalyKind> started = monitor.observe(step++, observation(0, 0, 20.0));
  ASSERT_EQ(started.size(), 1u);
  EXPECT_EQ(started[0], AnomalyKind::kSpeedBurst);
  EXPECT_GT(monitor.anomalies().back().peak, 10);
}

TEST(StepAnomalies, FlagsASpeedRampOfTensOfStepsAgainstTheSpeedBeforeIt) {
  // Steady at 0.5 m/s, then speeding up 20 % per step: the median of the last 50 steps would
  // follow the ramp, the median before them does not.
  StepAnomalyMonitor monitor;
  int step = 0;
  for (; step < 200; ++step)
    EXPECT_TRUE(monitor.observe(step, observation(0, 0, 0.5)).empty());
  double speed = 0.5;
  int burst_step = -1;
  for (int k = 1; k <= 30 && burst_step < 0; ++k, ++step) {
    speed *= 1.2;
    if (!monitor.observe(step, observation(0, 0, speed)).empty()) burst_step = k;
  }
  // 1.2^k > 10 first at k = 13.
  EXPECT_EQ(burst_step, 13);
}

TEST(StepAnomalies, NoSpeedBurstWhenABodyStartsFromRest) {
  // At rest for the whole history, then the slow speeds a hand gives: below the speed floor.
  StepAnomalyMonitor monitor;
  int step = 0;
  for (; step < 160; ++step)
    monitor.observe(step, observation(0, 0, 0));
  for (; step < 300; ++step)
    EXPECT_TRUE(monitor.observe(step, observation(0, 0, 0.5)).empty());
}

TEST(StepAnomalies, AConditionBackAfterALongGapOpensANewRange) {
  StepAnomalyMonitor monitor;
  StepObservation bad = observation(0, 0);
  bad.inverted_elements = 3;
  EXPECT_EQ(monitor.observe(1, bad).size(), 1u);
  EXPECT_TRUE(monitor.observe(5, bad).empty());  // within merge_gap_steps: the same range
  EXPECT_EQ(monitor.observe(100, bad).size(), 1u);
  ASSERT_EQ(monitor.anomalies().size(), 2u);
  EXPECT_EQ(monitor.anomalies()[0].last_step, 5);
  EXPECT_EQ(monitor.anomalies()[1].first_step, 100);
}

}  // namespace
}  // namespace torsion
