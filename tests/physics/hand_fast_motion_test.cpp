// The report's complaint (chapter 4): when the hand moves fast, tets with both grabbed and free
// nodes over-deform. Reproduced here with a 90 degree turn of the hand in three steps on the soft
// 2430-tet cylinder (E = 1e5 Pa, shear wave speed 6.2 m/s): the grabbed ring moves 0.5 m per
// 10 ms step while the material can carry the motion inward at 6 m/s, so the tets under it are
// sheared past inversion. It is physics, not a time-step artefact: the same turn at dt = 1 ms is no
// gentler (docs/hand-plane.md). The remedy is the hand's speed limit (HandSettings): the patch
// pursues the device frame at most at max_drag_strain x the shear wave speed, so the drag strain
// stays near that fraction. Writes hand_fast_turn.csv when TORSION_VALIDATION_OUT is set.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "torsion/analysis/deformation_metrics.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/mesh/mesh_io.h"
#include "validation_output.h"

namespace torsion {
namespace {

struct TurnHistory {
  std::vector<DeformationMetrics> per_step;
  double worst_strain = 0;
  int worst_inverted = 0;
  double max_grabbed_node_step = 0;  ///< m, largest travel of a grabbed node in one step
  double speed_limit = 0;            ///< m/s
  int steps_to_reach_goal = -1;      ///< first step whose patch frame equals the goal
  double final_strain = 0;
  int final_inverted = 0;
};

constexpr double kDt = 0.01;
constexpr int kTurnSteps = 3;    // the device turns 90 degrees in 30 ms
constexpr int kHoldSteps = 300;  // then holds still for 3 s

/// The cylinder (r = 1, L = 10), base fixed, a hand grabbing at z = 9.9 whose device frame turns
/// 90 degrees about the axis in kTurnSteps steps and then stays.
TurnHistory fastTurn(double max_drag_strain, double dt = kDt, int turn_steps = kTurnSteps,
                     int hold_steps = kHoldSteps) {
  Result<LoadedMesh> loaded = readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_2430.node");
  if (!loaded.ok()) {
    ADD_FAILURE() << loaded.error().message;
    return {};
  }
  const TetMesh& mesh = loaded.value().mesh;
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = dt;
  FemWorld world(settings);
  Material material;  // E = 1e5 Pa, nu = 0.3, rho = 1000 kg/m^3, beta = 0.01 s
  FemBody* body = world.addBody("cyl", mesh, material).value();
  std::vector<int> base;
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    if (mesh.restPositions()[static_cast<size_t>(n)].z() < 1e-9) base.push_back(n);
  }
  body->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0);

  HandSettings hand_settings;
  hand_settings.max_drag_strain = max_drag_strain;
  Hand hand(*body, "hand", hand_settings);
  Frame start;
  start.origin = Eigen::Vector3d(0, 0, 9.9);
  EXPECT_TRUE(hand.grab(start, 0).ok());

  TurnHistory history;
  history.speed_limit = hand.speedLimit();
  Eigen::VectorXd previous = body->state().positions;
  for (int step = 1; step <= turn_steps + hold_steps; ++step) {
    Frame device = start;
    const double angle = M_PI / 2 * std::min(1.0, static_cast<double>(step) / turn_steps);
    device.rotation = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ());
    EXPECT_TRUE(hand.moveTo(device).ok());
    const WorldStepReport report = world.step();
    EXPECT_TRUE(report.ok) << report.message;
    if (!report.ok) break;
    const Eigen::VectorXd& x = body->state().positions;
    for (int node : hand.grabbedNodes()) {
      history.max_grabbed_node_step =
          std::max(history.max_grabbed_node_step,
                   (x.segment<3>(3 * node) - previous.segment<3>(3 * node)).norm());
    }
    previous = x;
    if (history.steps_to_reach_goal < 0 && step >= turn_steps &&
        hand.frame().rotation.angularDistance(device.rotation) < 1e-12) {
      history.steps_to_reach_goal = step;
    }
    const DeformationMetrics metrics = measureDeformation(body->model(), x);
    history.per_step.push_back(metrics);
    history.worst_strain = std::max(history.worst_strain, metrics.max_strain);
    history.worst_inverted = std::max(history.worst_inverted, metrics.inverted_tets);
    history.final_strain = metrics.max_strain;
    history.final_inverted = metrics.inverted_tets;
  }
  return history;
}

TEST(HandFastMotion, UnlimitedFastTurnOverDeformsAndTheSpeedLimitPreventsIt) {
  const TurnHistory before = fastTurn(0.0);  // the patch lands on every device frame
  const TurnHistory after = fastTurn(0.2);   // the default limit

  if (auto csv = test::validationCsv("hand_fast_turn.csv",
                                     "time,strain_unlimited,inverted_unlimited,strain_limited,"
                                     "inverted_limited")) {
    for (size_t s = 0; s < std::min(before.per_step.size(), after.per_step.size()); ++s) {
      *csv << kDt * static_cast<double>(s + 1) << "," << before.per_step[s].max_strain << ","
           << before.per_step[s].inverted_tets << "," << after.per_step[s].max_strain << ","
           << after.per_step[s].inverted_tets << "\n";
    }
  }
  std::printf(
      "[figures] unlimited: worst strain %.3f, worst inverted %d; limited (%.2f m/s): "
      "worst strain %.3f, worst inverted %d, goal reached at step %d\n",
      before.worst_strain, before.worst_inverted, after.speed_limit, after.worst_strain,
      after.worst_inverted, after.steps_to_reach_goal);

  // Before: the report's over-deformation, reproduced (tets turned inside out, strains above 100 %)
  // — and it recovers once the hand stops: the inversion-safe rotations pull the tets back.
  EXPECT_GT(before.worst_inverted, 5);
  EXPECT_GT(before.worst_strain, 1.5);
  EXPECT_EQ(before.steps_to_reach_goal, kTurnSteps);
  EXPECT_EQ(before.final_inverted, 0);

  // Not a time-step artefact: the same 30 ms turn resolved with 1 ms steps is as bad.
  const TurnHistory fine = fastTurn(0.0, kDt / 10, 10 * kTurnSteps, 20);
  std::printf("[figures] unlimited at dt = 1 ms: worst strain %.3f, worst inverted %d\n",
              fine.worst_strain, fine.worst_inverted);
  // The volume barrier (fem/volume_barrier.h) keeps most of the 1 ms run's tets from inverting
  // (4 invert, 27 without it), not its strain.
  EXPECT_GT(fine.worst_inverted, 0);
  EXPECT_GT(fine.worst_strain, 1.5);

  // After: never a tet inverted, the worst strain within twice the limit's nominal drag strain
  // (the stop adds a ring-down overshoot); the same 90 degree twist of the rod at rest strains its
  // surface by about 0.16, so the limit costs a slower turn, not a different result.
  EXPECT_EQ(after.worst_inverted, 0);
  EXPECT_LT(after.worst_strain, 0.4);
  // No grabbed node ever moved faster than the limit (r = 1: 90 degrees take ~1.3 s).
  EXPECT_LE(after.max_grabbed_node_step, after.speed_limit * kDt * (1 + 1e-9));
  const double reach = std::hypot(1.0, 0.1);  // farthest grabbed node from O = (0, 0, 9.9)
  const int expected_steps =
      static_cast<int>(std::ceil(M_PI / 2 * reach / (after.speed_limit * kDt)));
  EXPECT_NEAR(after.steps_to_reach_goal, expected_steps, 2);
}

}  // namespace
}  // namespace torsion
