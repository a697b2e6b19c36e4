// The contact-space Coulomb solver (coulomb_problem.h) against closed forms: a particle on a plane
// (stick, slide and separate, on both sides of the friction limit), an anisotropic contact against
// an independent 1-D solve over the slip angle, a rigid box on an incline below and above
// atan(mu), warm start and the convergence report, bilateral anchors, and the cone projection.
#include "torsion/contact/coulomb_problem.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

namespace torsion {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Uniform in [lo, hi) from the raw 32-bit output of mt19937 (its sequence is fixed by the
// standard, unlike std::uniform_real_distribution's).
double uniform(std::mt19937& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng()) / 4294967296.0;
}

Eigen::Vector3d randomVector(std::mt19937& rng) {
  return {uniform(rng, -1, 1), uniform(rng, -1, 1), uniform(rng, -1, 1)};
}

// A random rotation (the Q of a random matrix's QR).
Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  Eigen::Matrix3d a;
  for (int c = 0; c < 3; ++c)
    a.col(c) = randomVector(rng);
  Eigen::Matrix3d q = a.householderQr().householderQ();
  if (q.determinant() < 0) q.col(0) = -q.col(0);
  return q;
}

// A random symmetric positive definite n x n matrix with the given eigenvalues.
Eigen::MatrixXd spdWithEigenvalues(std::mt19937& rng, const Eigen::VectorXd& eigenvalues) {
  const Eigen::Index n = eigenvalues.size();
  Eigen::MatrixXd a(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j)
      a(i, j) = uniform(rng, -1, 1);
  }
  const Eigen::MatrixXd q = a.householderQr().householderQ();
  return q * eigenvalues.asDiagonal() * q.transpose();
}

Eigen::Vector3d tangentialPart(const Eigen::Vector3d& n, const Eigen::Vector3d& v) {
  return v - n * n.dot(v);
}

// The angle (rad) between two non-zero vectors, accurate near zero.
double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

CoulombProblem oneContact(const Eigen::Matrix3d& w, const Eigen::Vector3d& free_velocity,
                          const Eigen::Vector3d& n, double mu) {
  CoulombProblem p;
  p.delassus = w;
  p.free_velocity = free_velocity;
  p.normal = {n};
  p.friction = {mu};
  return p;
}

// ---------------------------------------------------------------------------------------------
// 1. A particle of mass m on a static plane: W = I / m, so u = u_free + r / m. With u_free =
//    -v_n n + v_t t (v_n > 0 approaching, t a unit tangent):
//    stick  u = 0, r = -m u_free: r_n = m v_n, |r_t| = m v_t, admissible iff v_t <= mu v_n;
//    slide  u_n = 0 gives r_n = m v_n; r_t = -mu r_n t, so u_t = (v_t - mu r_n / m) t = (v_t -
//           mu v_n) t, along u_free's tangential part and positive iff v_t > mu v_n;
//    moving away (u_free . n > 0): r = 0, u = u_free.
// ---------------------------------------------------------------------------------------------

constexpr double kParticleMass = 2.0;  // kg
constexpr double kParticleMu = 0.5;
constexpr double kApproach = 0.3;  // m/s, v_n

struct ParticleOnPlane {
  Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();
  Eigen::Vector3d t = n.unitOrthogonal();
  CoulombProblem problem(double v_n, double v_t) const {
    return oneContact(Eigen::Matrix3d::Identity() / kParticleMass, -v_n * n + v_t * t, n,
                      kParticleMu);
  }
};

TEST(CoulombParticle, JustBelowTheFrictionLimitItSticksWithTheImpulseThatStopsIt) {
  const ParticleOnPlane plane;
  const double v_t = kParticleMu * kApproach * (1 - 1e-6);
  const CoulombProblem p = plane.problem(kApproach, v_t);
  Eigen::VectorXd r, u;
  const CoulombReport report = solveCoulomb(p, CoulombSettings{1e-12, 100}, r, u);
  ASSERT_TRUE(report.converged);
  EXPECT_LT(u.norm(), 1e-14);
  EXPECT_LT((r + kParticleMass * p.free_velocity).norm(), 1e-14);
  const Eigen::Vector3d ri = r.head<3>();
  EXPECT_LT(tangentialPart(plane.n, ri).norm(), kParticleMu * plane.n.dot(ri));
}

TEST(CoulombParticle, JustAboveTheFrictionLimitItSlidesWithFrictionAtTheLimit) {
  const ParticleOnPlane plane;
  const double v_t = kParticleMu * kApproach * (1 + 1e-6);
  const CoulombProblem p = plane.problem(kApproach, v_t);
  Eigen::VectorXd r, u;
  const CoulombReport report = solveCoulomb(p, CoulombSettings{1e-12, 100}, r, u);
  ASSERT_TRUE(report.converged);
  const Eigen::Vector3d ri = r.head<3>();
  const Eigen::Vector3d ui = u.head<3>();
  const double rn = plane.n.dot(ri);
  EXPECT_NEAR(rn, kParticleMass * kApproach, 1e-14);
  EXPECT_NEAR(tangentialPart(plane.n, ri).norm(), kParticleMu * rn, 1e-14);
  EXPECT_LT((tangentialPart(plane.n, ri) + kParticleMu * rn * plane.t).norm(), 1e-14);
  // The slip, 1.5e-7 m/s, along u_free's tangential part and reduced by mu r_n / m.
  const Eigen::Vector3d slip = (v_t - kParticleMu * rn / kParticleMass) * plane.t;
  EXPECT_GT(slip.norm(), 1e-7);
  EXPECT_LT((ui - slip).norm(), 1e-15);
}

TEST(CoulombParticle, WellAboveTheFrictionLimitTheSlipIsTheFreeSlipLessMuTimesTheApproach) {
  const ParticleOnPlane plane;
  const CoulombProblem p = plane.problem(kApproach, 2.0);
  Eigen::VectorXd r, u;
  ASSERT_TRUE(solveCoulomb(p, CoulombSettings{1e-12, 100}, r, u).converged);
  EXPECT_LT((u.head<3>() - (2.0 - kParticleMu * kApproach) * plane.t).norm(), 1e-14);
  EXPECT_LT((r.head<3>() - kParticleMass * kApproach * (plane.n - kParticleMu * plane.t)).norm(),
            1e-14);
}

TEST(CoulombParticle, MovingAwayFromThePlaneItFeelsNoImpulse) {
  const ParticleOnPlane plane;
  const CoulombProblem p = plane.problem(-0.1, 2.0);  // u_free . n = +0.1 m/s
  Eigen::VectorXd r, u;
  ASSERT_TRUE(solveCoulomb(p, CoulombSettings{1e-12, 100}, r, u).converged);
  EXPECT_EQ(r.norm(), 0.0);
  EXPECT_EQ((u - p.free_velocity).norm(), 0.0);
}

// ---------------------------------------------------------------------------------------------
// 2. One contact with an anisotropic W (eigenvalues 0.4, 1, 2.5 kg^-1, random axes), sliding.
//    Independent solution: a sliding answer is r = r_n (n - mu d) with d = cos(theta) e1 +
//    sin(theta) e2 the slip direction. For a trial theta, u_n = 0 fixes r_n = -u_free_n /
//    (n . W (n - mu d)); the slip v = (u_free + W r)_t must then be parallel to d with d . v > 0.
//    The root of theta -> n . (d x v) is found by a 1-D scan over [0, 2 pi) and bisection; no
//    projected Gauss-Seidel involved.
// ---------------------------------------------------------------------------------------------

struct SlidingAnswer {
  Eigen::Vector3d r;
  double slip;  // m/s, |u_t|
};

std::vector<SlidingAnswer> slidingAnswersByAngle(const Eigen::Matrix3d& w,
                                                 const Eigen::Vector3d& free_velocity,
                                                 const Eigen::Vector3d& n, double mu) {
  const Eigen::Vector3d e1 = n.unitOrthogonal();
  const Eigen::Vector3d e2 = n.cross(e1);
  struct Trial {
    Eigen::Vector3d r, slip_velocity;
    double cross, along;
    bool admissible;
  };
  auto trial = [&](double theta) {
    Trial tr;
    const Eigen::Vector3d d = std::cos(theta) * e1 + std::sin(theta) * e2;
    const Eigen::Vector3d direction = n - mu * d;
    const double rn = -n.dot(free_velocity) / n.dot(w * direction);
    tr.r = rn * direction;
    tr.slip_velocity = tangentialPart(n, free_velocity + w * tr.r);
    tr.cross = n.dot(d.cross(tr.slip_velocity));
    tr.along = d.dot(tr.slip_velocity);
    tr.admissible = rn > 0 && n.dot(w * direction) > 0;
    return tr;
  };
  std::vector<SlidingAnswer> answers;
  const int samples = 3600;
  for (int k = 0; k < samples; ++k) {
    double lo = 2 * kPi * k / samples;
    double hi = 2 * kPi * (k + 1) / samples;
    Trial a = trial(lo);
    const Trial b = trial(hi);
    if (!(a.cross <= 0 && b.cross > 0) && !(a.cross >= 0 && b.cross < 0)) continue;
    for (int it = 0; it < 200 && hi - lo > 1e-15; ++it) {
      const double mid = 0.5 * (lo + hi);
      const Trial m = trial(mid);
      if ((m.cross > 0) == (a.cross > 0)) {
        lo = mid;
        a = m;
      } else {
        hi = mid;
      }
    }
    const Trial root = trial(0.5 * (lo + hi));
    if (root.admissible && root.along > 0) answers.push_back({root.r, root.slip_velocity.norm()});
  }
  return answers;
}

TEST(CoulombAnisotropic, TheSlidingAnswerMatchesAnIndependentSolveOverTheSlipAngle) {
  std::mt19937 rng(20261124);
  const double mu = 0.4;
  int worst_sweeps = 0;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Matrix3d q = randomRotation(rng);
    const Eigen::Matrix3d w = q * Eigen::Vector3d(0.4, 1.0, 2.5).asDiagonal() * q.transpose();
    const Eigen::Vector3d n = randomVector(rng).normalized();
    const Eigen::Vector3d t = n.unitOrthogonal();
    // Approaching at 0.5 m/s, sliding at 2 m/s: far beyond the stick region here.
    const Eigen::Vector3d free_velocity = -0.5 * n + 2.0 * t;
    // Sticking is not a solution (the impulse that stops the contact leaves the cone), so the
    // sliding answer is the only one.
    const Eigen::Vector3d stop = -w.ldlt().solve(free_velocity);
    ASSERT_GT(tangentialPart(n, stop).norm(), mu * n.dot(stop));
    const std::vector<SlidingAnswer> reference = slidingAnswersByAngle(w, free_velocity, n, mu);
    ASSERT_EQ(reference.size(), 1u) << "case " << c;

    const CoulombProblem p = oneContact(w, free_velocity, n, mu);
    Eigen::VectorXd r, u;
    const CoulombSettings settings{1e-11, 2000};
    const CoulombReport report = solveCoulomb(p, settings, r, u);
    ASSERT_TRUE(report.converged) << "case " << c << ": " << report.residual;
    worst_sweeps = std::max(worst_sweeps, report.sweeps);
    const Eigen::Vector3d ri = r.head<3>();
    const Eigen::Vector3d ui = u.head<3>();
    const Eigen::Vector3d rt = tangentialPart(n, ri);
    const Eigen::Vector3d ut = tangentialPart(n, ui);

    EXPECT_LT(std::abs(n.dot(ui)), 1e-10) << "case " << c;
    // On the cone to rounding of the Newton steps (relative 1e-10 of the impulse).
    EXPECT_NEAR(rt.norm(), mu * n.dot(ri), 1e-10 * ri.norm()) << "case " << c;
    EXPECT_LT(angleBetween(rt, -ut), 1e-6) << "case " << c;
    EXPECT_LT(coulombResidual(n, mu, ri, ui, 1.0 / n.dot(w * n)), 1e-10) << "case " << c;
    // r's error is at most the residual (m/s) over W's smallest eigenvalue (0.4 / kg).
    EXPECT_LT((ri - reference[0].r).norm(), 1e-9) << "case " << c;
    EXPECT_NEAR(ut.norm(), reference[0].slip, 1e-9) << "case " << c;
  }
  RecordProperty("worst_sweeps", worst_sweeps);
}

TEST(CoulombAnisotropic, InsideTheFrictionConeTheAnswerIsTheImpulseThatStopsTheContact) {
  std::mt19937 rng(7);
  const double mu = 0.8;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Matrix3d q = randomRotation(rng);
    const Eigen::Matrix3d w = q * Eigen::Vector3d(0.4, 1.0, 2.5).asDiagonal() * q.transpose();
    const Eigen::Vector3d n = randomVector(rng).normalized();
    // The stopping impulse chosen inside the cone (|r_t| = 0.5 mu r_n), u_free = -W r.
    const Eigen::Vector3d stop = n + 0.5 * mu * n.unitOrthogonal();
    const CoulombProblem p = oneContact(w, -w * stop, n, mu);
    Eigen::VectorXd r, u;
    const CoulombReport report = solveCoulomb(p, CoulombSettings{1e-11, 2000}, r, u);
    ASSERT_TRUE(report.converged) << "case " << c;
    EXPECT_LT(u.norm(), 1e-10) << "case " << c;
    EXPECT_LT((r.head<3>() - stop).norm(), 1e-10 / 0.4) << "case " << c;
  }
}

// coulombResidual is zero on each of Coulomb's three states and positive off them; otherwise the
// residual checks above would prove nothing.
TEST(CoulombResidual, IsZeroOnCoulombsStatesAndPositiveOffThem) {
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  const double mu = 0.5;
  const double step = 0.7;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  // Separate, stick, slide (friction against the slip).
  EXPECT_EQ(coulombResidual(n, mu, Eigen::Vector3d::Zero(), {0.3, -1, 0.2}, step), 0.0);
  EXPECT_NEAR(coulombResidual(n, mu, {0.2, 0.1, 1}, Eigen::Vector3d::Zero(), step), 0, 1e-15);
  EXPECT_NEAR(coulombResidual(n, mu, {-0.5, 0, 1}, 2 * x, step), 0, 1e-15);
  // Friction along the slip, friction below the limit while slipping, a pull, a gap with impulse,
  // a penetrating velocity with no impulse.
  EXPECT_GT(coulombResidual(n, mu, {0.5, 0, 1}, 2 * x, step), 0.1);
  EXPECT_GT(coulombResidual(n, mu, {-0.2, 0, 1}, 2 * x, step), 0.1);
  EXPECT_GT(coulombResidual(n, mu, {0, 0, -1}, Eigen::Vector3d::Zero(), step), 0.1);
  EXPECT_GT(coulombResidual(n, mu, {0, 0, 1}, {0, 0, 0.5}, step), 0.1);
  EXPECT_GT(coulombResidual(n, mu, Eigen::Vector3d::Zero(), {0, 0, -0.5}, step), 0.1);
}

// ---------------------------------------------------------------------------------------------
// 3. A rigid box (mass M, half extents a, b, h) resting on its 4 bottom corners on a static plane
//    tilted by alpha. Plane normal n = (sin a, 0, cos a), downhill d = (cos a, 0, -sin a), gravity
//    (0, 0, -g). The box's velocity V = (v, w) after the step is V_free + M^-1 G^T r with
//    V_free = (g dt, 0) and G_k = [I, -[rho_k]x] (corner k at rho_k from the centre): W = G M^-1
//    G^T (12 x 12, rank 6) plus a compliance c I with c M = 1e-8. Rigid answer: below atan(mu)
//    the box stays at rest, sum r = -M g dt; above it slides, v . d = g dt (sin a - mu cos a)
//    (sum of normal impulses M g dt cos a, each corner's friction mu r_n against the common slip).
//    The compliance moves both by O(c M) relative. How the load splits among the corners is
//    statically indeterminate (it rests on c alone): the light corners may sit on the cone's edge
//    with a slip of order c r, so at rest every corner's velocity is checked to be that small
//    rather than each corner to be strictly inside the cone. Angles 0.02 rad (1.1 deg) either side.
// ---------------------------------------------------------------------------------------------

struct BoxOnIncline {
  double mass = 2.0;                                        // kg
  Eigen::Vector3d half = Eigen::Vector3d(0.1, 0.08, 0.05);  // m
  double gravity = 9.81;                                    // m/s^2
  double dt = 0.01;                                         // s
  double mu = 0.5;
  double compliance = 1e-8 / 2.0;  // s/kg, c M = 1e-8

  Eigen::Vector3d n, d;
  Eigen::MatrixXd g;       // G, 12 x 6
  Eigen::MatrixXd m_inv;   // 6 x 6
  Eigen::VectorXd v_free;  // 6

  explicit BoxOnIncline(double alpha) {
    n = Eigen::Vector3d(std::sin(alpha), 0, std::cos(alpha));
    d = Eigen::Vector3d(std::cos(alpha), 0, -std::sin(alpha));
    const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
    Eigen::Matrix3d rotation;  // box frame to world: x -> d, y -> y, z -> n
    rotation << d, y, n;
    const Eigen::Vector3d s = half.cwiseProduct(half);
    const Eigen::Vector3d principal =
        mass / 3 * Eigen::Vector3d(s.y() + s.z(), s.x() + s.z(), s.x() + s.y());
    const Eigen::Matrix3d inertia = rotation * principal.asDiagonal() * rotation.transpose();
    m_inv = Eigen::MatrixXd::Zero(6, 6);
    m_inv.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / mass;
    m_inv.bottomRightCorner<3, 3>() = inertia.inverse();
    g.resize(12, 6);
    int k = 0;
    for (double sx : {-1.0, 1.0}) {
      for (double sy : {-1.0, 1.0}) {
        const Eigen::Vector3d rho = sx * half.x() * d + sy * half.y() * y - half.z() * n;
        Eigen::Matrix3d cross;
        cross << 0, -rho.z(), rho.y(), rho.z(), 0, -rho.x(), -rho.y(), rho.x(), 0;
        g.block<3, 3>(3 * k, 0).setIdentity();
        g.block<3, 3>(3 * k, 3) = -cross;
        ++k;
      }
    }
    v_free = Eigen::VectorXd::Zero(6);
    v_free.head<3>() = Eigen::Vector3d(0, 0, -gravity * dt);
  }

  CoulombProblem problem() const {
    CoulombProblem p;
    p.delassus = g * m_inv * g.transpose() + compliance * Eigen::MatrixXd::Identity(12, 12);
    p.free_velocity = g * v_free;
    p.normal.assign(4, n);
    p.friction.assign(4, mu);
    return p;
  }
  Eigen::VectorXd velocityAfter(const Eigen::VectorXd& r) const {
    return v_free + m_inv * g.transpose() * r;
  }
};

Eigen::Vector3d sumOfImpulses(const Eigen::VectorXd& r) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int k = 0; k < r.size() / 3; ++k)
    sum += r.segment<3>(3 * k);
  return sum;
}

constexpr double kBoxAngleMargin = 0.02;          // rad
const CoulombSettings kBoxSettings{1e-10, 2000};  // m/s: 1e-9 of g dt

TEST(CoulombRigidBox, BelowTheFrictionAngleTheBoxStaysAtRest) {
  const BoxOnIncline box(std::atan(0.5) - kBoxAngleMargin);
  const CoulombProblem p = box.problem();
  Eigen::VectorXd r, u;
  const CoulombReport report = solveCoulomb(p, kBoxSettings, r, u);
  RecordProperty("sweeps", report.sweeps);
  ASSERT_TRUE(report.converged) << report.sweeps << " sweeps, residual " << report.residual;
  const double gravity_velocity = box.gravity * box.dt;  // m/s
  const double gravity_impulse = box.mass * gravity_velocity;
  EXPECT_LT((sumOfImpulses(r) - Eigen::Vector3d(0, 0, gravity_impulse)).norm(),
            1e-6 * gravity_impulse);
  const Eigen::VectorXd v = box.velocityAfter(r);
  EXPECT_LT(v.head<3>().norm(), 1e-6 * gravity_velocity);
  EXPECT_LT(v.tail<3>().norm() * box.half.norm(), 1e-6 * gravity_velocity);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d rk = r.segment<3>(3 * k);
    EXPECT_GT(box.n.dot(rk), 0) << "corner " << k;
    EXPECT_LE(tangentialPart(box.n, rk).norm(), box.mu * box.n.dot(rk) * (1 + 1e-12))
        << "corner " << k;
    EXPECT_LT(u.segment<3>(3 * k).norm(), 1e-6 * gravity_velocity) << "corner " << k;
  }
}

TEST(CoulombRigidBox, AboveTheFrictionAngleTheBoxSlidesAtCoulombsAcceleration) {
  const double alpha = std::atan(0.5) + kBoxAngleMargin;
  const BoxOnIncline box(alpha);
  const CoulombProblem p = box.problem();
  Eigen::VectorXd r, u;
  const CoulombReport report = solveCoulomb(p, kBoxSettings, r, u);
  RecordProperty("sweeps", report.sweeps);
  ASSERT_TRUE(report.converged) << report.sweeps << " sweeps, residual " << report.residual;
  const Eigen::VectorXd v = box.velocityAfter(r);
  const double expected =
      box.gravity * box.dt * (std::sin(alpha) - box.mu * std::cos(alpha));  // m/s, 2.2 mm/s
  EXPECT_NEAR(box.d.dot(v.head<3>()), expected, 1e-6 * expected);
  EXPECT_LT(std::abs(box.n.dot(v.head<3>())), 1e-6 * expected);
  EXPECT_NEAR(box.n.dot(sumOfImpulses(r)), box.mass * box.gravity * box.dt * std::cos(alpha),
              1e-6 * box.mass * box.gravity * box.dt);
  for (int k = 0; k < 4; ++k) {
    const Eigen::Vector3d rk = r.segment<3>(3 * k);
    const Eigen::Vector3d uk = u.segment<3>(3 * k);
    EXPECT_NEAR(tangentialPart(box.n, rk).norm(), box.mu * box.n.dot(rk), 1e-12) << k;
    EXPECT_LT(angleBetween(tangentialPart(box.n, uk), box.d), 1e-6) << "corner " << k;
    EXPECT_LT(angleBetween(tangentialPart(box.n, rk), -box.d), 1e-6) << "corner " << k;
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Two coupled contacts (W a random SPD 6 x 6): the report, and a warm start from the answer.
// ---------------------------------------------------------------------------------------------

CoulombProblem twoCoupledContacts() {
  std::mt19937 rng(42);
  Eigen::VectorXd eigenvalues(6);
  eigenvalues << 0.2, 0.5, 0.8, 1.0, 1.5, 3.0;
  CoulombProblem p;
  p.delassus = spdWithEigenvalues(rng, eigenvalues);
  p.normal = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d(0.3, 0, 1).normalized()};
  p.friction = {0.3, 0.6};
  p.free_velocity.resize(6);
  p.free_velocity << 1.0, 0.2, -0.5, -0.1, 0.05, -0.4;
  return p;
}

TEST(CoulombReport, AConvergedAnswerHasEveryContactsResidualBelowTheTolerance) {
  const CoulombProblem p = twoCoupledContacts();
  const CoulombSettings settings{1e-10, 2000};
  Eigen::VectorXd r, u;
  const CoulombReport report = solveCoulomb(p, settings, r, u);
  RecordProperty("sweeps", report.sweeps);
  ASSERT_TRUE(report.converged);
  EXPECT_GT(report.sweeps, 1);
  EXPECT_LE(report.residual, settings.tolerance);
  // Recomputed here from the returned impulses alone.
  const Eigen::VectorXd velocity = p.free_velocity + p.delassus * r;
  EXPECT_LT((velocity - u).norm(), 1e-14);
  for (int i = 0; i < 2; ++i) {
    const Eigen::Vector3d& n = p.normal[static_cast<size_t>(i)];
    const double step = 1.0 / n.dot(p.delassus.block<3, 3>(3 * i, 3 * i) * n);
    EXPECT_LE(coulombResidual(n, p.friction[static_cast<size_t>(i)], r.segment<3>(3 * i),
                              velocity.segment<3>(3 * i), step),
              settings.tolerance * (1 + 1e-6))
        << "contact " << i;
  }
}

TEST(CoulombReport, AWarmStartFromTheAnswerConvergesWithoutWork) {
  const CoulombProblem p = twoCoupledContacts();
  const CoulombSettings settings{1e-10, 2000};
  Eigen::VectorXd r, u;
  ASSERT_TRUE(solveCoulomb(p, settings, r, u).converged);
  const Eigen::VectorXd answer = r;
  const CoulombReport again = solveCoulomb(p, settings, r, u);
  EXPECT_TRUE(again.converged);
  // The answer is checked before any sweep or Newton step: it is returned as it came.
  EXPECT_EQ(again.sweeps, 0);
  EXPECT_EQ(again.newton_steps, 0);
  EXPECT_LT((r - answer).norm(), 1e-8);
}

TEST(CoulombReport, TooFewSweepsReportNotConverged) {
  const CoulombProblem p = twoCoupledContacts();
  Eigen::VectorXd r, u;
  const CoulombReport full = solveCoulomb(p, CoulombSettings{1e-10, 2000}, r, u);
  ASSERT_TRUE(full.converged);
  ASSERT_GT(full.sweeps, 2);
  r.resize(0);
  const CoulombReport cut = solveCoulomb(p, CoulombSettings{1e-10, 2}, r, u);
  EXPECT_FALSE(cut.converged);
  EXPECT_EQ(cut.sweeps, 2);
  EXPECT_GT(cut.residual, 1e-10);
  EXPECT_LT((u - (p.free_velocity + p.delassus * r)).norm(), 1e-14);
}

TEST(CoulombReport, NoContactsIsConvergedWithoutASweep) {
  CoulombProblem p;
  p.delassus.resize(0, 0);
  p.free_velocity.resize(0);
  Eigen::VectorXd r = Eigen::VectorXd::Ones(3), u;
  const CoulombReport report = solveCoulomb(p, CoulombSettings{}, r, u);
  EXPECT_TRUE(report.converged);
  EXPECT_EQ(report.sweeps, 0);
  EXPECT_EQ(r.size(), 0);
}

// ---------------------------------------------------------------------------------------------
// 5. Bilateral contacts (anchors): u = 0 whatever the sign of r, so r = -W^-1 u_free.
// ---------------------------------------------------------------------------------------------

TEST(CoulombBilateral, TwoCoupledAnchorsHoldWithTheImpulsesThatStopThemEvenPulling) {
  std::mt19937 rng(3);
  Eigen::VectorXd eigenvalues(6);
  eigenvalues << 0.1, 0.4, 0.9, 1.0, 2.0, 5.0;
  CoulombProblem p;
  p.delassus = spdWithEigenvalues(rng, eigenvalues);
  p.normal = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ()};
  p.friction = {0.0, 0.0};  // irrelevant to an anchor
  p.bilateral = {1, 1};
  p.free_velocity.resize(6);
  p.free_velocity << 0.3, -0.2, 1.0, -0.4, 0.1, 0.8;  // both moving away from their normals
  Eigen::VectorXd r, u;
  const CoulombReport report = solveCoulomb(p, CoulombSettings{1e-11, 2000}, r, u);
  RecordProperty("sweeps", report.sweeps);
  ASSERT_TRUE(report.converged);
  EXPECT_LT(u.norm(), 1e-10);
  const Eigen::VectorXd held = -p.delassus.ldlt().solve(p.free_velocity);
  EXPECT_LT((r - held).norm(), 1e-10 / 0.1);
  EXPECT_LT(std::min(r[2], r[5]), -0.1);  // at least one anchor pulls
}

// An anchor beside a frictional contact that separates: the contact takes no impulse, so the
// anchor alone stops its own velocity, r_anchor = -W_11^-1 u_free_1; the coupling moves the
// other contact away (checked, so that separating is Coulomb's answer).
TEST(CoulombBilateral, AnAnchorBesideASeparatingContactHoldsAlone) {
  std::mt19937 rng(5);
  Eigen::VectorXd eigenvalues(6);
  eigenvalues << 0.3, 0.5, 0.9, 1.2, 2.0, 2.5;
  CoulombProblem p;
  p.delassus = spdWithEigenvalues(rng, eigenvalues);
  p.normal = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ()};
  p.friction = {0.5, 0.5};
  p.bilateral = {1, 0};
  p.free_velocity.resize(6);
  p.free_velocity << 0.2, 0.1, 0.6, 0.3, -0.2, 2.0;
  const Eigen::Vector3d anchor =
      -p.delassus.topLeftCorner<3, 3>().ldlt().solve(p.free_velocity.head<3>());
  const Eigen::Vector3d other =
      p.free_velocity.tail<3>() + p.delassus.bottomLeftCorner<3, 3>() * anchor;
  ASSERT_GT(other.z(), 0);
  Eigen::VectorXd r, u;
  ASSERT_TRUE(solveCoulomb(p, CoulombSettings{1e-11, 2000}, r, u).converged);
  EXPECT_LT((r.head<3>() - anchor).norm(), 1e-10);
  EXPECT_EQ(r.tail<3>().norm(), 0.0);
  EXPECT_LT(u.head<3>().norm(), 1e-10);
  EXPECT_LT((u.tail<3>() - other).norm(), 1e-10);
}

// ---------------------------------------------------------------------------------------------
// 6. projectOntoCone: the Euclidean projection onto K = {|r_t| <= mu r_n}. Moreau: P r is it iff
//    P r in K, r - P r in the polar cone K° = {mu |x_t| <= -x_n}, and (r - P r) . P r = 0.
// ---------------------------------------------------------------------------------------------

TEST(CoulombCone, PointsInsideAndOnTheBoundaryAreLeftAlone) {
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, -0.5).normalized();
  const Eigen::Vector3d t = n.unitOrthogonal();
  const Eigen::Vector3d inside = 2 * n + 0.3 * t;
  EXPECT_EQ(projectOntoCone(n, 0.5, inside), inside);
  const Eigen::Vector3d boundary = 2 * n + 1.0 * t;  // |r_t| = mu r_n
  EXPECT_LT((projectOntoCone(n, 0.5, boundary) - boundary).norm(), 1e-15);
  EXPECT_EQ(projectOntoCone(n, 0.5, Eigen::Vector3d::Zero()), Eigen::Vector3d::Zero());
}

TEST(CoulombCone, ThePolarConeProjectsToZero) {
  const Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
  // mu |r_t| <= -r_n: (1, 0, -0.5) with mu 0.5, on the polar boundary; (0, 0, -1) deep inside.
  EXPECT_EQ(projectOntoCone(n, 0.5, {1, 0, -0.5}), Eigen::Vector3d::Zero());
  EXPECT_EQ(projectOntoCone(n, 0.5, {0, 0, -1}), Eigen::Vector3d::Zero());
  // Between the two cones: onto the boundary ray, here r = (2, 0, 0) with mu = 1 gives (1, 0, 1).
  EXPECT_LT((projectOntoCone(n, 1.0, {2, 0, 0}) - Eigen::Vector3d(1, 0, 1)).norm(), 1e-15);
}

TEST(CoulombCone, WithoutFrictionItKeepsOnlyAPushingNormalPart) {
  const Eigen::Vector3d n = Eigen::Vector3d(0, 0.6, 0.8);
  const Eigen::Vector3d t = n.unitOrthogonal();
  EXPECT_LT((projectOntoCone(n, 0, 1.5 * n + 3 * t) - 1.5 * n).norm(), 1e-15);
  EXPECT_EQ(projectOntoCone(n, 0, -1.5 * n + 3 * t), Eigen::Vector3d::Zero());
  EXPECT_EQ(projectOntoCone(n, 0, 3 * t), Eigen::Vector3d::Zero());
}

TEST(CoulombCone, OnRandomVectorsItIsIdempotentAndSatisfiesMoreausDecomposition) {
  std::mt19937 rng(11);
  for (int k = 0; k < 2000; ++k) {
    const Eigen::Vector3d n = randomVector(rng).normalized();
    const double mu = k % 10 == 0 ? 0.0 : uniform(rng, 0.05, 2.0);
    const Eigen::Vector3d r = 3 * randomVector(rng);
    const Eigen::Vector3d p = projectOntoCone(n, mu, r);
    const Eigen::Vector3d x = r - p;
    const double eps = 1e-12;
    EXPECT_LE(tangentialPart(n, p).norm(), mu * n.dot(p) + eps) << k;
    EXPECT_LE(mu * tangentialPart(n, x).norm(), -n.dot(x) + eps) << k;
    EXPECT_NEAR(x.dot(p), 0, eps) << k;
    EXPECT_LT((projectOntoCone(n, mu, p) - p).norm(), eps) << k;
  }
}

}  // namespace
}  // namespace torsion
