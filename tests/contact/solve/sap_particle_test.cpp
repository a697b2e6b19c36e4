// A particle resting on a plane under gravity (docs/contact-sap.md): it sticks below Coulomb's
// threshold, slides with Coulomb's deceleration above it at its rest height, keeps its speed
// without friction. Every loop carries each contact's normal impulse to the next step's row (the
// lagged model's friction bound).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sap_test_support.h"

namespace torsion::sap {
// Named, not anonymous: its constants share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace sap_particle_test {

constexpr double kMass = 1.0;
constexpr double kDt = 1e-3;
constexpr double kStiffness = 1e6;  // N/m: a static deflection of m g / k = 9.8 um
constexpr double kTauD = 2e-3;      // s: about critical damping, 2 sqrt(m / k)

struct ParticleRun {
  double mean_friction_ratio = 0;  // sum |gamma_t| / sum gamma_n
  double worst_ratio_error = 0;    // max over sliding steps of | |gamma_t| / (mu gamma_n) - 1 |
  double max_stick_speed = 0;      // the largest |v_t| while stuck, after 0.1 s
  double max_stick_slip = 0;       // its regularised value R_t |gamma_t| there
  double velocity_x = 0;           // at the end
  double position_z = 0;
  double max_lift = 0;  // the largest height above the static deflection
  int slide_steps = 0, stick_steps = 0;
  int max_newton = 0;
};

// The particle starts at rest at its static deflection (its contact carrying m g dt from the
// steps before); a constant push f_x for `steps` steps.
ParticleRun runParticle(double mu, double push, double v0_x, int steps) {
  Eigen::Vector3d x(0, 0, -kMass * test::kGravity / kStiffness);
  Eigen::Vector3d v(v0_x, 0, 0);
  const Eigen::Vector3d force(push, 0, -kMass * test::kGravity);
  ContactRow row;
  row.frame = contactFrame(Eigen::Vector3d::UnitZ());
  row.terms.push_back(nodeTerm(0, 0, 1.0, row.frame));
  row.mu = mu;
  row.stiffness = kStiffness;
  row.dissipation_time = kTauD;
  row.lagged_normal_impulse = kMass * test::kGravity * kDt;
  SapSolver solver;
  ParticleRun run;
  double sum_t = 0, sum_n = 0;
  for (int step = 0; step < steps; ++step) {
    MatrixBody particle(test::massMatrix({kMass}), kMass * v + kDt * force);
    row.gap = x.z();
    const SapProblem problem = SapProblem::create({&particle}, {row}, kDt).value();
    Eigen::VectorXd next = v;  // warm start
    const SapReport report = solver.solve(problem, next);
    test::expectCoulombAndComplementarity(problem, report);
    const Eigen::Vector3d& gamma = report.impulses[0];
    run.max_newton = std::max(run.max_newton, report.newton_iterations);
    sum_t += gamma.head<2>().norm();
    sum_n += gamma(2);
    if (report.states[0] == ContactState::kSlide) {
      ++run.slide_steps;
      run.worst_ratio_error =
          std::max(run.worst_ratio_error,
                   std::abs(gamma.head<2>().norm() / (mu * row.lagged_normal_impulse) - 1));
    } else if (report.states[0] == ContactState::kStick) {
      ++run.stick_steps;
      if (step * kDt >= 0.1) {
        run.max_stick_speed = std::max(run.max_stick_speed, next.head<2>().norm());
        run.max_stick_slip =
            std::max(run.max_stick_slip, problem.model(0).rt * gamma.head<2>().norm());
      }
    }
    row.lagged_normal_impulse = gamma(2);
    v = next;
    x += kDt * v;
    run.max_lift = std::max(run.max_lift, x.z() + kMass * test::kGravity / kStiffness);
  }
  run.mean_friction_ratio = sum_t / sum_n;
  run.velocity_x = v.x();
  run.position_z = x.z();
  return run;
}

// A push of 0.4 mu m g: static friction holds it. The only tangential motion left is the
// regularised stiction slip v_t = -R_t gamma_t (R_t = 1e-3 w), whose steady value is
// R_t f dt: about a micrometre per second.
TEST(SapParticle, SticksBelowCoulombsThreshold) {
  const double mu = 0.5, push = 0.4 * mu * kMass * test::kGravity;
  const ParticleRun run = runParticle(mu, push, 0.0, 1000);
  EXPECT_EQ(run.slide_steps, 0);
  EXPECT_EQ(run.stick_steps, 1000);
  const double rt = 1e-3 * std::sqrt(3.0) / 3 / kMass;
  EXPECT_NEAR(run.max_stick_speed, rt * push * kDt, 1e-3 * rt * push * kDt);
  EXPECT_LE(run.max_stick_speed, run.max_stick_slip * (1 + 1e-9));
  EXPECT_LT(run.max_stick_speed, 2e-6);
  // Resting at its static deflection.
  EXPECT_NEAR(run.position_z, -kMass * test::kGravity / kStiffness, 1e-3 * 9.81e-6);
  std::printf("particle stick: |v_t| = %.3e m/s, R_t f dt = %.3e m/s; Newton <= %d\n",
              run.max_stick_speed, rt * push * kDt, run.max_newton);
}

// A push of 2 mu m g: it slides from the first step, friction exactly mu times the previous step's
// normal impulse in every step (the disk's circle, 1e-12), which is m g dt, and after 1 s its speed
// is (f / m - mu g) t.
TEST(SapParticle, SlidesWithCoulombsDecelerationAboveIt) {
  const double mu = 0.5, push = 2 * mu * kMass * test::kGravity;
  const ParticleRun run = runParticle(mu, push, 0.0, 1000);
  EXPECT_EQ(run.slide_steps, 1000);
  EXPECT_LT(run.worst_ratio_error, 1e-12);
  EXPECT_NEAR(run.mean_friction_ratio, mu, 1e-9 * mu);
  const double expected = (push / kMass - mu * test::kGravity) * 1.0;
  EXPECT_NEAR(run.velocity_x, expected, 1e-6 * expected);
  std::printf(
      "particle slide: v(1 s) = %.6f m/s, Coulomb %.6f; worst |gamma_t|/(mu gamma_n)-1 = "
      "%.2e; Newton <= %d\n",
      run.velocity_x, expected, run.worst_ratio_error, run.max_newton);
}

// A sliding contact rides at its rest height: the normal impulse is the compliant law's alone,
// so at 4.9 m/s the particle stays at its static deflection m g / k (the exact cone's convex
// relaxation lifted it (dt + tau_d) mu |v_t| = 7.4 mm). Held to 1e-3 of the deflection (10 nm).
TEST(SapParticle, SlidingRidesAtItsRestHeight) {
  const double mu = 0.5, push = 2 * mu * kMass * test::kGravity;
  const ParticleRun run = runParticle(mu, push, 0.0, 1000);
  const double deflection = kMass * test::kGravity / kStiffness;
  const double lift = run.position_z + deflection;
  EXPECT_LT(std::abs(lift), 1e-3 * deflection);
  EXPECT_LT(run.max_lift, 1e-3 * deflection);
  std::printf(
      "particle slide at %.2f m/s: rides %.2e m above rest (max %.2e; exact cone's dilation "
      "(dt + tau_d) mu v_t = %.3f mm)\n",
      run.velocity_x, lift, run.max_lift, 1e3 * (kDt + kTauD) * mu * run.velocity_x);
}

// A particle resting on a conveyor belt that starts at 1 m/s (a kinematic partner: the belt's
// velocity enters the row as its velocity offset): friction accelerates it at mu g until it runs
// with the belt, at t = v / (mu g) = 0.204 s, and from then on it sticks to the belt. The sudden
// 1 m/s slip does not lift it (the exact cone's relaxation made it hop 5.5 mm, 58 ms airborne):
// the contact never separates, the particle never rises above its static deflection by more than
// 1e-3 of it, its normal speed stays below 1e-6 m/s, and its speed at 0.1 s is mu g t to 1e-9.
TEST(SapParticle, ConveyorBeltCarriesItAfterCoulombsRunUpWithoutHopping) {
  const double mu = 0.5, belt = 1.0, deflection = kMass * test::kGravity / kStiffness;
  Eigen::Vector3d x(0, 0, -deflection), v = Eigen::Vector3d::Zero();
  ContactRow row;
  row.frame = contactFrame(Eigen::Vector3d::UnitZ());
  row.terms.push_back(nodeTerm(0, 0, 1.0, row.frame));
  row.mu = mu;
  row.stiffness = kStiffness;
  row.dissipation_time = kTauD;
  row.velocity_offset = -row.frame * Eigen::Vector3d(belt, 0, 0);  // B the particle, A the belt
  row.lagged_normal_impulse = kMass * test::kGravity * kDt;        // resting before the start
  SapSolver solver;
  double speed_at_100ms = 0, max_lift = 0, max_normal_speed = 0;
  int airborne = 0;
  SapReport report;
  for (int step = 0; step < 500; ++step) {
    MatrixBody particle(test::massMatrix({kMass}),
                        kMass * v + kDt * Eigen::Vector3d(0, 0, -kMass * test::kGravity));
    row.gap = x.z();
    const SapProblem problem = SapProblem::create({&particle}, {row}, kDt).value();
    Eigen::VectorXd next = v;
    report = solver.solve(problem, next);
    test::expectCoulombAndComplementarity(problem, report);
    if (step < 200) {  // still running up to the belt's speed: never stuck
      EXPECT_EQ(report.states[0], ContactState::kSlide) << "step " << step;
    }
    airborne += report.impulses[0](2) == 0;
    row.lagged_normal_impulse = report.impulses[0](2);
    v = next;
    x += kDt * v;
    max_lift = std::max(max_lift, x.z() + deflection);
    max_normal_speed = std::max(max_normal_speed, std::abs(v.z()));
    if (step + 1 == 100) speed_at_100ms = v.x();
  }
  EXPECT_EQ(airborne, 0);
  EXPECT_LT(max_lift, 1e-3 * deflection);
  EXPECT_LT(max_normal_speed, 1e-6);
  EXPECT_NEAR(speed_at_100ms, mu * test::kGravity * 0.1, 1e-9 * mu * test::kGravity * 0.1);
  EXPECT_EQ(report.states[0], ContactState::kStick);
  EXPECT_NEAR(v.x(), belt, 1e-6);
  std::printf(
      "conveyor: v(0.1 s) = %.9f m/s (mu g t = %.9f); v(0.5 s) = %.8f m/s, belt %.1f; "
      "airborne %d steps, lift <= %.2e m, |v_n| <= %.2e m/s\n",
      speed_at_100ms, mu * test::kGravity * 0.1, v.x(), belt, airborne, max_lift, max_normal_speed);
}

TEST(SapParticle, FrictionlessKeepsItsTangentialSpeed) {
  const ParticleRun run = runParticle(0.0, 0.0, 2.0, 1000);
  EXPECT_NEAR(run.velocity_x, 2.0, 1e-12);
  EXPECT_NEAR(run.position_z, -kMass * test::kGravity / kStiffness, 1e-3 * 9.81e-6);
}

// A particle held to a fixed point by a bilateral row (an anchor, ContactRow::bilateral): the row
// pulls as well as pushes. Hanging under gravity it settles m g / k below the point with the row
// carrying m g dt; displaced 1 cm sideways without gravity, it returns as the critically damped
// spring-damper (tau_d = 2 sqrt(m / k)): no overshoot, within 1 um in 0.1 s.
struct AnchoredRun {
  Eigen::Vector3d x = Eigen::Vector3d::Zero();
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();  // N s on the particle, world, last step
  double overshoot = 0;                               // m, furthest past the point along x
};

AnchoredRun runAnchored(const Eigen::Vector3d& start, double gravity, int steps) {
  Eigen::Vector3d x = start, v = Eigen::Vector3d::Zero();
  AnchoredRun run;
  SapSolver solver;
  for (int step = 0; step < steps; ++step) {
    const Eigen::Vector3d drift = -x;  // the fixed point is the origin
    const double distance = drift.norm();
    ContactRow row;
    row.frame =
        contactFrame(distance > 0 ? Eigen::Vector3d(drift / distance) : Eigen::Vector3d::UnitZ());
    row.terms.push_back(nodeTerm(0, 0, 1.0, row.frame));
    row.kind = RowKind::kAnchor;
    row.stiffness = kStiffness;
    row.dissipation_time = kTauD;
    row.gap = -distance;
    MatrixBody particle(test::massMatrix({kMass}),
                        kMass * v + kDt * Eigen::Vector3d(0, 0, -kMass * gravity));
    const SapProblem problem = SapProblem::create({&particle}, {row}, kDt).value();
    Eigen::VectorXd next = v;
    const SapReport report = solver.solve(problem, next);
    EXPECT_TRUE(report.converged) << report.message;
    EXPECT_EQ(report.states[0], ContactState::kStick);
    run.impulse = row.frame.transpose() * report.impulses[0];
    v = next;
    x += kDt * v;
    run.overshoot = std::max(run.overshoot, -x.x());
  }
  run.x = x;
  return run;
}

TEST(SapParticle, AnAnchoredParticleHangsAtItsSpringsDeflection) {
  const AnchoredRun run = runAnchored(Eigen::Vector3d::Zero(), test::kGravity, 1000);
  EXPECT_NEAR(run.x.z(), -kMass * test::kGravity / kStiffness, 1e-9);
  EXPECT_NEAR(run.x.head<2>().norm(), 0.0, 1e-12);
  EXPECT_NEAR(run.impulse.z(), kMass * test::kGravity * kDt, 1e-6 * kMass * test::kGravity * kDt);
}

TEST(SapParticle, AnAnchoredParticlePulledAsideReturnsWithoutOvershoot) {
  const AnchoredRun run = runAnchored(Eigen::Vector3d(0.01, 0, 0), 0.0, 100);
  EXPECT_LT(run.x.norm(), 1e-6);
  EXPECT_LT(run.overshoot, 1e-4);  // 1 % of the pull
}
}  // namespace sap_particle_test
}  // namespace torsion::sap
