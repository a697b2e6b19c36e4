// Hyperelastic bodies under homogeneous finite strain, stepped by the implicit stepper in statics
// (docs/materials.md, "Validation"): uniaxial tension to stretch 2 and simple shear to gamma = 1.
// A homogeneous deformation lies in the span of tet4's and tet10's shape functions and, with
// boundary conditions that allow it, is the discrete body's exact equilibrium: the whole step (the
// element passes, the Newton solve, the constraints) must reproduce the law's closed forms to the
// solve's tolerance, on any mesh. The law-level closed forms are hyperelastic_test.cpp's.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "torsion/fem/fem_model.h"
#include "torsion/fem/hyperelastic.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/implicit_stepper.h"
#include "torsion/solve/parallel.h"

namespace torsion {
namespace {
// Named: the unity build puts this file beside others with helpers of the same names.
namespace homogeneous {

constexpr double kYoung = 1e5;
// Under AddressSanitizer the memory checks need one element kind (the tet10 pass has its own in
// hyperelastic_step_test.cpp); the Release suite runs both.
#if defined(__SANITIZE_ADDRESS__) || (defined(__has_feature) && __has_feature(address_sanitizer))
constexpr ElementKind kElements[] = {ElementKind::kTet4};
#else
constexpr ElementKind kElements[] = {ElementKind::kTet4, ElementKind::kTet10};
#endif

Material rubber(MaterialLaw law, double nu) {
  Material m;
  m.youngs_modulus = kYoung;
  m.poisson_ratio = nu;
  m.law = law;
  m.mooney_rivlin_c2_fraction = 0.3;
  m.stiffness_damping = 0;  // statics: the reactions are the elastic forces alone
  m.barrier_threshold = 0;  // the law alone
  return m;
}

SolverSettings statics() {
  SolverSettings s;
  s.time_step = 1000;  // the mass's share of the system is 1e-6 * rho / (E dt^2): statics
  s.linear_solver = LinearSolverKind::kCholmod;
  s.newton_tolerance = 1e-10;
  s.newton_max_iterations = 50;
  return s;
}

Eigen::Matrix3d piola(const Material& m, const Eigen::Matrix3d& F) {
  if (m.law == MaterialLaw::kMooneyRivlin) {
    return firstPiola(MooneyRivlin::fromYoungPoisson(m.youngs_modulus, m.poisson_ratio,
                                                     m.mooney_rivlin_c2_fraction),
                      F);
  }
  return firstPiola(StableNeoHookean::fromYoungPoisson(m.youngs_modulus, m.poisson_ratio), F);
}

// The lateral stretch s of F = diag(s, s, stretch) with P_11 = 0 (secant steps on the law's
// stress: it is monotone in s).
double lateralStretch(const Material& m, double stretch) {
  auto p11 = [&](double s) { return piola(m, Eigen::Vector3d(s, s, stretch).asDiagonal())(0, 0); };
  double a = 1 / std::sqrt(stretch), b = 1.0, fa = p11(a), fb = p11(b);
  for (int it = 0; it < 100 && std::abs(fb) > 1e-14 * kYoung && fb != fa; ++it) {
    const double c = b - fb * (b - a) / (fb - fa);
    a = b;
    fa = fb;
    b = c;
    fb = p11(b);
  }
  return b;
}

struct Loaded {
  double max_position_error = 0;  ///< m, against the homogeneous deformation
  double end_force = 0;           ///< N, or J (simple shear: the elastic energy)
  int newton_max = 0;
  bool converged = true;
};

// A box [0, hi] of nx x ny x nz cells stepped in statics by its own implicit stepper; step()
// records each step's Newton verdict in `loaded`.
struct StaticBox {
  StaticBox(const Material& m, ElementKind element, const Eigen::Vector3d& hi, int nx, int ny,
            int nz)
      : model(FemModel::create(std::make_shared<TetMesh>(
                                   makeBoxTetMesh(Eigen::Vector3d::Zero(), hi, nx, ny, nz).value()),
                               m, element)
                  .value()),
        stepper(model, statics(), parallel),
        state(FemState::atRest(*model)) {}

  const std::vector<Eigen::Vector3d>& rest() const { return model->mesh().restPositions(); }
  // The velocity that takes node i to `target` over the step.
  Eigen::Vector3d towards(int i, const Eigen::Vector3d& target) const {
    return (target - state.position(i)) / statics().time_step;
  }
  StepReport step(const NodeConstraints& c) {
    const StepReport report = stepper.step(state, c, Eigen::VectorXd::Zero(3 * model->nodeCount()));
    EXPECT_EQ(report.health, StepHealth::kOk) << report.message;
    loaded.converged = loaded.converged && report.newton.converged;
    loaded.newton_max = std::max(loaded.newton_max, report.newton.iterations);
    return report;
  }
  // The farthest node from where `exact` (of its rest position) puts it, m.
  template <class Exact>
  void measureAgainst(Exact exact) {
    for (int i = 0; i < model->nodeCount(); ++i) {
      const Eigen::Vector3d target = exact(rest()[static_cast<size_t>(i)]);
      loaded.max_position_error =
          std::max(loaded.max_position_error, (state.position(i) - target).norm());
    }
  }

  std::shared_ptr<const FemModel> model;
  Parallel parallel{1};
  ImplicitStepper stepper;
  FemState state;
  Loaded loaded;
};

// A 1 x 1 x 2 bar (2 x 2 x 4 cells) stretched along z to `stretch` in `increments` statics steps.
// Rollers: the base's nodes move in x and y only, the top's too while it rises; the node at the
// origin is held, and (1, 0, 1), on a traction-free edge, keeps y = 0 (no rigid motion left, and
// no constraint the homogeneous stretch does not meet with zero reaction). Reports the force the
// top nodes carry along z, against P_33 of the law times the rest area 1 m^2.
Loaded stretchBar(const Material& m, ElementKind element, double stretch, int increments) {
  StaticBox bar(m, element, Eigen::Vector3d(1, 1, 2), 2, 2, 4);
  const std::vector<Eigen::Vector3d>& rest = bar.rest();
  const int n = bar.model->nodeCount();
  for (int k = 1; k <= increments; ++k) {
    const double length = 2 * (1 + (stretch - 1) * k / increments);
    NodeConstraints c(n);
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d& x = rest[static_cast<size_t>(i)];
      if (x.z() < 1e-9) c.prescribeDirection(i, Eigen::Vector3d::UnitZ(), 0);
      if (x.z() > 2 - 1e-9) {
        c.prescribeDirection(i, Eigen::Vector3d::UnitZ(),
                             bar.towards(i, Eigen::Vector3d(0, 0, length)).z());
      }
    }
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d& x = rest[static_cast<size_t>(i)];
      if (x.norm() < 1e-9) c.prescribeVelocity(i, Eigen::Vector3d::Zero());
      if ((x - Eigen::Vector3d(1, 0, 1)).norm() < 1e-9)
        c.prescribeDirection(i, Eigen::Vector3d::UnitY(), 0);
    }
    bar.step(c);
  }
  const double s = lateralStretch(m, stretch);
  bar.measureAgainst([&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(s * x.x(), s * x.y(), stretch * x.z());
  });
  const Eigen::VectorXd& f = bar.stepper.internalForces();
  for (int i = 0; i < n; ++i)
    if (rest[static_cast<size_t>(i)].z() > 2 - 1e-9) bar.loaded.end_force -= f(3 * i + 2);
  return bar.loaded;
}

// Every case of the homogeneous tests: both laws, nu = 0.3 and 0.499, each element of kElements;
// check(material, element, label).
template <class Check>
void forEveryCase(Check check) {
  for (MaterialLaw law : {MaterialLaw::kStableNeoHookean, MaterialLaw::kMooneyRivlin}) {
    for (double nu : {0.3, 0.499}) {
      for (ElementKind element : kElements) {
        char label[64];
        std::snprintf(label, sizeof label, "%s nu %.3f %s", toString(law), nu,
                      element == ElementKind::kTet10 ? "tet10" : "tet4");
        SCOPED_TRACE(label);
        check(rubber(law, nu), element, label);
      }
    }
  }
}

// Stretch 2 at nu = 0.3 and 0.499, both laws, tet4 and tet10: every node where the homogeneous
// stretch puts it (1e-9 of the bar's length, the Newton tolerance's reach), and the end force the
// law's nominal stress P_33 of that stretch (1e-8 relative). At nu = 0.499 the nominal stress is
// also the incompressible closed form's, mu (l - l^-2) (neo-Hookean) or 2 (C1 + C2 / l)
// (l - l^-2) (Mooney-Rivlin), within the volume change's share (hyperelastic_test.cpp: 1/7000 and
// 1e-4). Measured: nodes within 5.8e-10 m, the force within 2e-10 of P_33, -1.43e-4 and
// +1.85e-5 from the incompressible forms.
TEST(HyperelasticHomogeneous, UniaxialTensionToStretchTwoCarriesTheLawsNominalStress) {
  const double l = 2.0;
  forEveryCase([l](const Material& m, ElementKind element, const char* label) {
    const Loaded r = stretchBar(m, element, l, 8);
    const double s = lateralStretch(m, l);
    const double nominal = piola(m, Eigen::Vector3d(s, s, l).asDiagonal())(2, 2);
    const MooneyRivlin mr = MooneyRivlin::fromYoungPoisson(kYoung, m.poisson_ratio, 0.3);
    const double incompressible = m.law == MaterialLaw::kMooneyRivlin
                                      ? 2 * (mr.c1 + mr.c2 / l) * (l - 1 / (l * l))
                                      : m.mu() * (l - 1 / (l * l));
    std::printf(
        "%s: end force %.6f N, law's P_33 %.6f Pa, incompressible %.6f Pa (%+.2e), lateral "
        "stretch %.6f, node error %.1e m, Newton max %d\n",
        label, r.end_force, nominal, incompressible, nominal / incompressible - 1, s,
        r.max_position_error, r.newton_max);
    EXPECT_TRUE(r.converged);
    EXPECT_LT(r.max_position_error, 2e-9);
    EXPECT_NEAR(r.end_force, nominal, 1e-8 * nominal);
    if (m.poisson_ratio > 0.49) {
      // Neo-Hookean: relative (mu / l')(1 - 1/l) / (l^3 - 1) = 1/7000 (hyperelastic_test.cpp).
      const double lp = StableNeoHookean::fromYoungPoisson(kYoung, m.poisson_ratio).lambda;
      const double bound = m.law == MaterialLaw::kMooneyRivlin
                               ? 1e-4
                               : 1.01 * (m.mu() / lp) * (1 - 1 / l) / (l * l * l - 1);
      EXPECT_NEAR(nominal / incompressible, 1, bound);
    }
  });
}

// A unit cube (2 x 2 x 2 cells) sheared to x = X + gamma Y with every boundary node carried there
// in `increments` statics steps; the interior nodes (the centre, and tet10's mid-edge nodes
// inside) are free. Both laws are exactly incompressible neo-Hookean or Mooney-Rivlin at J = 1,
// where Psi = mu gamma^2 / 2: the body's energy is that times its volume, and its derivative the
// shear stress mu gamma (hyperelastic_test.cpp checks the stress and the normal stress
// differences at the law level).
Loaded shearCube(const Material& m, ElementKind element, double gamma, int increments) {
  StaticBox cube(m, element, Eigen::Vector3d::Ones(), 2, 2, 2);
  auto onBoundary = [](const Eigen::Vector3d& x) {
    return x.minCoeff() < 1e-9 || x.maxCoeff() > 1 - 1e-9;
  };
  auto sheared = [](const Eigen::Vector3d& x, double g) {
    return Eigen::Vector3d(x.x() + g * x.y(), x.y(), x.z());
  };
  // One more step at the final gamma: its start's elastic energy is the sheared cube's.
  for (int k = 1; k <= increments + 1; ++k) {
    const double g = gamma * std::min(k, increments) / increments;
    NodeConstraints c(cube.model->nodeCount());
    for (int i = 0; i < cube.model->nodeCount(); ++i) {
      const Eigen::Vector3d& x = cube.rest()[static_cast<size_t>(i)];
      if (onBoundary(x)) c.prescribeVelocity(i, cube.towards(i, sheared(x, g)));
    }
    cube.loaded.end_force = cube.step(c).elastic_energy;
  }
  cube.measureAgainst([&](const Eigen::Vector3d& x) { return sheared(x, gamma); });
  return cube.loaded;
}

TEST(HyperelasticHomogeneous, SimpleShearToGammaOneStoresMuGammaSquaredOverTwo) {
  const double gamma = 1.0;
  forEveryCase([gamma](const Material& m, ElementKind element, const char* label) {
    const Loaded r = shearCube(m, element, gamma, 4);
    const double exact = m.mu() * gamma * gamma / 2;  // J, on the 1 m^3 cube
    std::printf("%s: energy %.6f J, mu gamma^2 V / 2 = %.6f J, node error %.1e m, Newton max %d\n",
                label, r.end_force, exact, r.max_position_error, r.newton_max);
    EXPECT_TRUE(r.converged);
    EXPECT_LT(r.max_position_error, 1e-9);
    EXPECT_NEAR(r.end_force, exact, 1e-8 * exact);
  });
}

}  // namespace homogeneous
}  // namespace
}  // namespace torsion
