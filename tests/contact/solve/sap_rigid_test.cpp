// Rigid bodies in SAP islands (docs/contact-sap.md): a box on an incline sticks below the
// friction angle and slides with Coulomb's acceleration above it; a node squeezed between two
// rigid plates holds or slides as Coulomb says; a stack of three boxes stands at its static
// deflection.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "sap_test_support.h"

namespace torsion::sap {
namespace sap_rigid_test {

using test::BoxState;
using test::kGravity;

const double kPi = std::acos(-1.0);
constexpr double kDt = 1e-3;
constexpr double kBoxStiffness = 1e5;  // N/m per corner
constexpr double kBoxTauD = 2e-3;      // s

// A row between a rigid box's bottom corner and the plane z = 0.
ContactRow groundRow(int body, const BoxState& box, const Eigen::Vector3d& corner, double mu) {
  ContactRow row;
  row.frame = contactFrame(Eigen::Vector3d::UnitZ());
  row.terms.push_back(rigidPointTerm(body, corner - box.position, +1, row.frame));
  row.mu = mu;
  row.stiffness = kBoxStiffness;
  row.dissipation_time = kBoxTauD;
  row.gap = corner.z();
  return row;
}

struct InclineRun {
  double creep_speed = 0;     // mean down-slope speed over the measured window, m/s
  double acceleration = 0;    // mean down-slope acceleration over the window, m/s^2
  double max_stick_slip = 0;  // the largest regularised stiction slip R_t |gamma_t|, m/s
  double distance = 0;        // down-slope, from the start, m
  int max_newton = 0, max_cg = 0;
};

// The incline is the plane z = 0 with gravity tilted by `angle`: down-slope is +x. The box starts
// at rest touching it; the window is [1 s, end].
InclineRun runIncline(double angle, double mu, double seconds) {
  const Eigen::Vector3d gravity(kGravity * std::sin(angle), 0, -kGravity * std::cos(angle));
  BoxState box;
  box.position.z() = box.half.z();
  SapSolver solver;
  InclineRun run;
  double x1 = 0, v1 = 0;
  std::vector<double> lagged;  // each corner's normal impulse of the previous step
  const int steps = static_cast<int>(std::lround(seconds / kDt));
  const int window = static_cast<int>(std::lround(1.0 / kDt));
  for (int step = 0; step < steps; ++step) {
    if (step == window) {
      x1 = box.position.x();
      v1 = box.twist(0);
    }
    const RigidBody body(box.mass, box.inertia(), box.momentum(gravity, kDt));
    std::vector<ContactRow> rows;
    for (const Eigen::Vector3d& corner : box.bottomCorners())
      rows.push_back(groundRow(0, box, corner, mu));
    test::carryLaggedImpulses(lagged, rows);
    const SapProblem problem = SapProblem::create({&body}, rows, kDt).value();
    Eigen::VectorXd v = box.twist;
    const SapReport report = solver.solve(problem, v);
    test::expectCoulombAndComplementarity(problem, report);
    lagged = test::normalImpulses(report);
    run.max_newton = std::max(run.max_newton, report.newton_iterations);
    run.max_cg = std::max(run.max_cg, report.cg_iterations);
    for (int i = 0; i < problem.rowCount(); ++i)
      if (report.states[static_cast<size_t>(i)] == ContactState::kStick && step >= window)
        run.max_stick_slip = std::max(
            run.max_stick_slip,
            problem.model(i).rt * report.impulses[static_cast<size_t>(i)].head<2>().norm());
    box.advance(v, kDt);
  }
  const double span = seconds - 1.0;
  run.creep_speed = (box.position.x() - x1) / span;
  run.acceleration = (box.twist(0) - v1) / span;
  run.distance = box.position.x();
  return run;
}

// One degree below the friction angle: it stays, creeping only by the regularised stiction slip
// (R_t = 1e-3 w: micrometres per second), far below 0.1 mm/s.
TEST(SapRigidBox, SticksOnAnInclineBelowTheFrictionAngle) {
  const double mu = 0.5, angle = std::atan(mu) - kPi / 180;
  const InclineRun run = runIncline(angle, mu, 3.0);
  EXPECT_LT(std::abs(run.creep_speed), 1e-4);
  EXPECT_LE(std::abs(run.creep_speed), 1.5 * run.max_stick_slip);
  std::printf(
      "box stick at %.3f deg: creep %.3e m/s (stiction slip R_t|gamma_t| %.3e); Newton <= "
      "%d, CG <= %d\n",
      angle * 180 / kPi, run.creep_speed, run.max_stick_slip, run.max_newton, run.max_cg);
}

// One degree above it and at 35 degrees: it slides with g (sin a - mu cos a).
TEST(SapRigidBox, SlidesWithCoulombsAccelerationAboveTheFrictionAngle) {
  const double mu = 0.5;
  for (double angle : {std::atan(mu) + kPi / 180, 35 * kPi / 180}) {
    const InclineRun run = runIncline(angle, mu, 2.5);
    const double expected = kGravity * (std::sin(angle) - mu * std::cos(angle));
    EXPECT_NEAR(run.acceleration, expected, 0.03 * expected) << "angle " << angle;
    // From rest at t = 0, 2.5 s, to 3 %: the contacts are new, so the first step has no friction
    // and adds g sin a dt t (11 mm, +1.9 % at 1 deg above; +0.24 % at 35 deg).
    const double distance = 0.5 * expected * 2.5 * 2.5;
    EXPECT_NEAR(run.distance, distance, 0.03 * distance) << "angle " << angle;
    std::printf("box slide at %.3f deg: %.5f m in 2.5 s, Coulomb %.5f (%+.2f %%)\n",
                angle * 180 / kPi, run.distance, distance, 100 * (run.distance / distance - 1));
    std::printf(
        "box slide at %.3f deg: a = %.5f m/s^2, Coulomb %.5f (%+.2f %%); Newton <= %d, CG "
        "<= %d\n",
        angle * 180 / kPi, run.acceleration, expected, 100 * (run.acceleration / expected - 1),
        run.max_newton, run.max_cg);
  }
}

// A contact far stiffer than the step can resolve (k = 1e12 N/m): R_n is the near-rigid cap
// beta^2 / (4 pi^2) w, and the box comes to rest on it without chatter: after 1 s nothing moves,
// the impulses repeat step after step, and each corner rests where the capped compliance puts it,
// phi = -(dt + tau_d) R_n gamma_n (v_n = 0 in gamma_n = (v_hat - v_n) / R_n); both to within ten
// times the solve's relative tolerance (1e-6), which is what each step's solve is held to.
TEST(SapRigidBox, NearRigidContactRestsWithoutChatter) {
  const Eigen::Vector3d gravity(0, 0, -kGravity);
  BoxState box;
  box.position.z() = box.half.z() + 1e-3;  // dropped from 1 mm
  SapSolver solver;
  double max_speed = 0, max_impulse_change = 0, worst_rest_error = 0;
  std::vector<double> last_normal(4, 0.0);
  for (int step = 0; step < 1500; ++step) {
    const RigidBody body(box.mass, box.inertia(), box.momentum(gravity, kDt));
    std::vector<ContactRow> rows;
    for (const Eigen::Vector3d& corner : box.bottomCorners()) {
      rows.push_back(groundRow(0, box, corner, 0.5));
      rows.back().stiffness = 1e12;
      rows.back().dissipation_time = 0;
    }
    test::carryLaggedImpulses(last_normal, rows);
    const SapProblem problem = SapProblem::create({&body}, rows, kDt).value();
    Eigen::VectorXd v = box.twist;
    const SapReport report = solver.solve(problem, v);
    test::expectCoulombAndComplementarity(problem, report);
    for (size_t i = 0; i < 4 && step >= 1000; ++i) {
      const RowModel& m = problem.model(static_cast<int>(i));
      EXPECT_GT(m.rn, 1.0 / (kDt * kDt * 1e12));  // the cap, not the stiffness, sets R_n
      const double gn = report.impulses[i](2);
      max_impulse_change = std::max(max_impulse_change, std::abs(gn - last_normal[i]) / gn);
      const double rest = -kDt * m.rn * gn;
      worst_rest_error = std::max(worst_rest_error, std::abs(rows[i].gap / rest - 1));
    }
    for (size_t i = 0; i < 4; ++i)
      last_normal[i] = report.impulses[i](2);
    if (step >= 1000) max_speed = std::max(max_speed, v.cwiseAbs().maxCoeff());
    box.advance(v, kDt);
  }
  EXPECT_LT(max_speed, 1e-9);
  EXPECT_LT(max_impulse_change, 1e-5);
  EXPECT_LT(worst_rest_error, 1e-5);
  std::printf("near-rigid box: |v| <= %.1e m/s, impulse change <= %.1e, rest depth error %.1e\n",
              max_speed, max_impulse_change, worst_rest_error);
}

// A box dropped flat from 5 cm with 3 m/s along x lands (about 1 m/s normal) and slides on for
// 0.3 s. Its corners' rows exist from the start; in the air their normal impulse is 0, so the
// first contact step has no friction bound (no lagged impulse): the impact's friction comes one
// step late, in full. The physical bound is Coulomb's on the totals: the tangential momentum lost
// never exceeds mu times the normal impulse received (1e-9); the box sliding throughout, the lag
// withholds only the last step's share: the loss is mu (sum of normal impulses - the last step's)
// to 1e-6. (Bounding the first step's friction by that step's own normal impulse instead, from a
// first solve without friction, counts the impact twice, this step and the next: it exceeds
// Coulomb's total by 3 % at k = 1e5 N/m and 17 % near-rigid; docs/contact-sap.md, "Limits".)
struct LandingRun {
  double coulomb_total = 0;  // mu times the sum of normal impulses, N s
  double lagged_total = 0;   // mu times the sum of all but the last step's
  double momentum_loss = 0;  // m (v0_x - v_x), N s
  double speed = 0;          // v_x at the end
  double loss_after_10ms = 0, coulomb_after_10ms = 0;  // 10 ms after the first normal impulse
  int max_newton = 0;
};

LandingRun runLanding(double stiffness, double tau_d) {
  const double mu = 0.5, v0 = 3.0;
  BoxState box;
  box.position.z() = box.half.z() + 0.05;
  box.twist(0) = v0;
  SapSolver solver;
  LandingRun run;
  std::vector<double> lagged;
  double normal_total = 0, last_normal = 0;
  int touched = -1;
  for (int step = 0; step < 300; ++step) {
    const RigidBody body(box.mass, box.inertia(),
                         box.momentum(Eigen::Vector3d(0, 0, -kGravity), kDt));
    std::vector<ContactRow> rows;
    for (const Eigen::Vector3d& corner : box.bottomCorners()) {
      rows.push_back(groundRow(0, box, corner, mu));
      rows.back().stiffness = stiffness;
      rows.back().dissipation_time = tau_d;
    }
    test::carryLaggedImpulses(lagged, rows);
    const SapProblem problem = SapProblem::create({&body}, rows, kDt).value();
    Eigen::VectorXd v = box.twist;
    const SapReport report = solver.solve(problem, v);
    test::expectCoulombAndComplementarity(problem, report);
    run.max_newton = std::max(run.max_newton, report.newton_iterations);
    lagged = test::normalImpulses(report);
    last_normal = 0;
    for (double g : lagged)
      last_normal += g;
    normal_total += last_normal;
    if (touched < 0 && last_normal > 0) touched = step;
    box.advance(v, kDt);
    if (touched >= 0 && step == touched + 10) {
      run.loss_after_10ms = box.mass * (v0 - box.twist(0));
      run.coulomb_after_10ms = mu * normal_total;
    }
  }
  run.coulomb_total = mu * normal_total;
  run.lagged_total = mu * (normal_total - last_normal);
  run.speed = box.twist(0);
  run.momentum_loss = box.mass * (v0 - run.speed);
  return run;
}

TEST(SapRigidBox, LandingWithTangentialSpeedStaysWithinCoulombsBound) {
  for (double stiffness : {kBoxStiffness, 1e12}) {
    const LandingRun run = runLanding(stiffness, stiffness > 1e6 ? 0.0 : kBoxTauD);
    EXPECT_GT(run.speed, 1.0);  // still sliding
    EXPECT_LE(run.momentum_loss, run.coulomb_total * (1 + 1e-9));
    EXPECT_NEAR(run.momentum_loss, run.lagged_total, 1e-6 * run.lagged_total);
    std::printf(
        "box landing (k %.0e N/m): momentum lost %.5f N s, mu sum gamma_n %.5f (%+.2f %%); 10 "
        "ms after touching %.5f vs %.5f; Newton <= %d\n",
        stiffness, run.momentum_loss, run.coulomb_total,
        100 * (run.momentum_loss / run.coulomb_total - 1), run.loss_after_10ms,
        run.coulomb_after_10ms, run.max_newton);
  }
}

// A node (0.1 kg) between two thin rigid plates (1 kg each, pressed together by F = 10 N, no
// gravity), pulled sideways by f. The plates' huge rotational inertia keeps them level (the rows
// take their surfaces as fixed planes). Co-moving needs friction f M / (m + 2 M) at each face:
// below mu F the three move together at f / (m + 2 M); above it the node slides through at
// (f - 2 mu F) / m and drags each plate at mu F / M.
struct SqueezeRun {
  double node_acceleration = 0, plate_acceleration = 0;
  double max_relative_speed = 0;  // node against the plates, after 0.05 s
  double lower_gap = 0, upper_gap = 0;
};

// The two rows on the node (body 0): the lower plate's top (body 1) below it, the upper plate's
// bottom (body 2) above it, both thin (their surfaces through their centres of mass).
std::vector<ContactRow> squeezeRows(const Eigen::Vector3d& node, const Eigen::Vector3d& lower,
                                    const Eigen::Vector3d& upper) {
  const Eigen::Matrix3d frame = contactFrame(Eigen::Vector3d::UnitZ());
  std::vector<ContactRow> rows(2);
  for (ContactRow& row : rows) {
    row.frame = frame;
    row.mu = 0.5;
    row.stiffness = 1e5;
    row.dissipation_time = 1e-3;
  }
  const Eigen::Vector3d below(node.x() - lower.x(), node.y() - lower.y(), 0);
  const Eigen::Vector3d above(node.x() - upper.x(), node.y() - upper.y(), 0);
  rows[0].terms = {nodeTerm(0, 0, +1, frame), rigidPointTerm(1, below, -1, frame)};
  rows[0].gap = node.z() - lower.z();
  rows[1].terms = {rigidPointTerm(2, above, +1, frame), nodeTerm(0, 0, -1, frame)};
  rows[1].gap = upper.z() - node.z();
  return rows;
}

SqueezeRun runSqueeze(double pull, double seconds) {
  const double m = 0.1, plate_mass = 1.0, press = 10.0;
  const Eigen::Matrix3d plate_inertia = 1e6 * Eigen::Matrix3d::Identity();
  // The node at the origin, each plate's surface pressed into it by its static deflection
  // F / k = 1e-4 m; v stacks the node's velocity and the plates' twists.
  Eigen::Vector3d node = Eigen::Vector3d::Zero(), lower(0, 0, 1e-4), upper(0, 0, -1e-4);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(15), v_start;
  SapSolver solver;
  SqueezeRun run;
  std::vector<double> lagged;  // each face's normal impulse of the previous step
  const int steps = static_cast<int>(std::lround(seconds / kDt));
  const int start = static_cast<int>(std::lround(0.05 / kDt));
  for (int step = 0; step < steps; ++step) {
    if (step == start) v_start = v;
    Eigen::VectorXd lower_b = plate_mass * v.segment<6>(3);
    Eigen::VectorXd upper_b = plate_mass * v.segment<6>(9);
    lower_b(2) += kDt * press;
    upper_b(2) -= kDt * press;
    MatrixBody particle(test::massMatrix({m}), m * v.head<3>() + kDt * Eigen::Vector3d(pull, 0, 0));
    const RigidBody lower_body(plate_mass, plate_inertia, lower_b);
    const RigidBody upper_body(plate_mass, plate_inertia, upper_b);
    std::vector<ContactRow> rows = squeezeRows(node, lower, upper);
    test::carryLaggedImpulses(lagged, rows);
    const SapProblem problem =
        SapProblem::create({&particle, &lower_body, &upper_body}, rows, kDt).value();
    const SapReport report = solver.solve(problem, v);
    test::expectCoulombAndComplementarity(problem, report);
    lagged = test::normalImpulses(report);
    node += kDt * v.head<3>();
    lower += kDt * v.segment<3>(3);
    upper += kDt * v.segment<3>(9);
    if (step >= start)
      run.max_relative_speed =
          std::max({run.max_relative_speed, (v.head<2>() - v.segment<2>(3)).norm(),
                    (v.head<2>() - v.segment<2>(9)).norm()});
  }
  const double span = seconds - 0.05;
  run.node_acceleration = (v(0) - v_start(0)) / span;
  run.plate_acceleration = (v(3) - v_start(3)) / span;
  run.lower_gap = node.z() - lower.z();
  run.upper_gap = upper.z() - node.z();
  return run;
}

TEST(SapSqueeze, NodeHoldsBetweenTwoRigidPlatesBelowCoulomb) {
  const SqueezeRun run = runSqueeze(5.0, 0.5);  // needs 2.38 N per face, holds 5 N
  const double common = 5.0 / (0.1 + 2 * 1.0);
  EXPECT_NEAR(run.node_acceleration, common, 0.01 * common);
  EXPECT_NEAR(run.plate_acceleration, common, 0.01 * common);
  EXPECT_LT(run.max_relative_speed, 1e-4);
  // Both faces hold the node at the static deflection F / k: neither passes through it.
  EXPECT_NEAR(run.lower_gap, -1e-4, 1e-6);
  EXPECT_NEAR(run.upper_gap, -1e-4, 1e-6);
  std::printf(
      "squeeze hold: a = %.5f / %.5f m/s^2 (common %.5f); slip <= %.2e m/s; gaps %.4e, "
      "%.4e m\n",
      run.node_acceleration, run.plate_acceleration, common, run.max_relative_speed, run.lower_gap,
      run.upper_gap);
}

TEST(SapSqueeze, NodeSlidesBetweenTwoRigidPlatesAboveCoulomb) {
  const SqueezeRun run = runSqueeze(11.0, 0.2);  // needs 5.24 N per face, holds 5 N
  EXPECT_NEAR(run.node_acceleration, (11.0 - 2 * 0.5 * 10.0) / 0.1, 0.01 * 10.0);
  EXPECT_NEAR(run.plate_acceleration, 0.5 * 10.0 / 1.0, 0.01 * 5.0);
  std::printf("squeeze slide: node a = %.4f (Coulomb 10), plate a = %.4f (Coulomb 5) m/s^2\n",
              run.node_acceleration, run.plate_acceleration);
}

// The stack's rows: the bottom box's corners on the ground, each upper box's bottom corners on
// the top face of the box below (rigid-rigid rows); level[i] is row i's level (0: the ground).
std::vector<ContactRow> stackRows(const std::vector<BoxState>& boxes, std::vector<int>& level) {
  constexpr double kTau = 1e-2;  // about critical for the stack's heaviest mode
  std::vector<ContactRow> rows;
  for (const Eigen::Vector3d& corner : boxes[0].bottomCorners()) {
    rows.push_back(groundRow(0, boxes[0], corner, 0.5));
    level.push_back(0);
  }
  for (int j = 1; j < static_cast<int>(boxes.size()); ++j) {
    const BoxState& a = boxes[static_cast<size_t>(j - 1)];
    const BoxState& b = boxes[static_cast<size_t>(j)];
    const Eigen::Vector3d n = a.rotation().col(2);
    const Eigen::Vector3d top = a.position + a.half.z() * n;
    for (const Eigen::Vector3d& corner : b.bottomCorners()) {
      ContactRow row;
      row.frame = contactFrame(n);
      row.gap = (corner - top).dot(n);
      const Eigen::Vector3d on_a = corner - row.gap * n;
      row.terms = {rigidPointTerm(j - 1, on_a - a.position, -1, row.frame),
                   rigidPointTerm(j, corner - b.position, +1, row.frame)};
      row.mu = 0.5;
      row.stiffness = kBoxStiffness;
      rows.push_back(row);
      level.push_back(j);
    }
  }
  for (ContactRow& row : rows)
    row.dissipation_time = kTau;
  return rows;
}

// Three 1 kg boxes stacked on the ground (rigid-rigid rows between them), 3 s: each level sinks to
// its static deflection (load / 4 corners / k) and no further; nothing slides or tilts.
TEST(SapStack, ThreeBoxesStandAtTheirStaticDeflection) {
  const Eigen::Vector3d gravity(0, 0, -kGravity);
  std::vector<BoxState> boxes(3);
  for (int j = 0; j < 3; ++j)
    boxes[static_cast<size_t>(j)].position.z() = (2 * j + 1) * boxes[0].half.z();
  SapSolver solver;
  std::vector<double> depth_at_1s(3, 0.0), depth(3, 0.0), worst(3, 0.0);
  std::vector<double> lagged;  // each row's normal impulse of the previous step
  int max_newton = 0;
  for (int step = 0; step < 3000; ++step) {
    std::vector<RigidBody> bodies;
    std::vector<const IslandBody*> island;
    Eigen::VectorXd v(18);
    for (size_t j = 0; j < 3; ++j) {
      bodies.emplace_back(boxes[j].mass, boxes[j].inertia(), boxes[j].momentum(gravity, kDt));
      v.segment<6>(6 * static_cast<int>(j)) = boxes[j].twist;
    }
    for (const RigidBody& body : bodies)
      island.push_back(&body);
    std::vector<int> level;
    std::vector<ContactRow> rows = stackRows(boxes, level);
    test::carryLaggedImpulses(lagged, rows);
    const SapProblem problem = SapProblem::create(island, rows, kDt).value();
    const SapReport report = solver.solve(problem, v);
    test::expectCoulombAndComplementarity(problem, report);
    lagged = test::normalImpulses(report);
    max_newton = std::max(max_newton, report.newton_iterations);
    std::fill(depth.begin(), depth.end(), 0.0);
    for (size_t i = 0; i < rows.size(); ++i) {
      const auto l = static_cast<size_t>(level[i]);
      depth[l] += -rows[i].gap / 4;
      if (step >= 1000) worst[l] = std::max(worst[l], -rows[i].gap);
    }
    if (step == 1000) depth_at_1s = depth;
    for (int j = 0; j < 3; ++j)
      boxes[static_cast<size_t>(j)].advance(v.segment<6>(6 * j), kDt);
  }
  for (int l = 0; l < 3; ++l) {
    const auto k = static_cast<size_t>(l);
    const double load = (3 - l) * kGravity;  // the boxes above level l, 1 kg each
    const double deflection = load / (4 * kBoxStiffness);
    EXPECT_NEAR(depth[k], deflection, 0.01 * deflection) << "level " << l;
    EXPECT_LE(worst[k], 1.01 * deflection) << "level " << l;
    EXPECT_LE(std::abs(depth[k] - depth_at_1s[k]), 1e-3 * deflection) << "level " << l;
    std::printf("stack level %d: depth %.4e m, m g / k per corner %.4e m, growth 1-3 s %.1e m\n", l,
                depth[k], deflection, depth[k] - depth_at_1s[k]);
  }
  for (const BoxState& box : boxes) {
    EXPECT_LT(box.position.head<2>().norm(), 1e-9);
    EXPECT_LT(Eigen::AngleAxisd(box.orientation).angle(), 1e-9);
  }
  std::printf("stack: Newton <= %d\n", max_newton);
}

}  // namespace sap_rigid_test
}  // namespace torsion::sap
