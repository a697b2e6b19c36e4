// St-Venant torsion of the cylinder assets (r = 1, L = 10; docs/design.md section 5): one end
// fixed, the other turned about the axis. Away from the ends each section turns rigidly, the angle
// is linear in z, and the torque through every section is T = G J theta'. J is the polar moment of
// the meshed (polygonal) section, computed exactly from the tets; theta' is fitted over the
// middle 60 %.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <tuple>

#include "torsion/analysis/twist_profile.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/mesh/mesh_io.h"
#include "validation_output.h"

namespace torsion {
namespace {

constexpr double kLength = 10;

TetMesh cylinder(int tets) {
  const std::string path =
      std::string(TORSION_ASSETS_DIR) + "/cylinder_" + std::to_string(tets) + ".node";
  Result<LoadedMesh> loaded = readMesh(path);
  if (!loaded.ok()) {
    ADD_FAILURE() << loaded.error().message;
    return TetMesh();
  }
  return std::move(loaded).value().mesh;
}

std::vector<int> nodesAtZ(const TetMesh& mesh, double z) {
  std::vector<int> nodes;
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    if (std::abs(mesh.restPositions()[static_cast<size_t>(i)].z() - z) < 1e-6) nodes.push_back(i);
  }
  return nodes;
}

std::vector<double> sliceCentres(double spacing) {
  std::vector<double> z;
  for (double c = 0; c <= kLength + 1e-9; c += spacing)
    z.push_back(c);
  return z;
}

FrameMotion turnAboutZ(std::function<double(double)> angle) {
  return [angle](double t) {
    Frame f;
    f.rotation = Eigen::AngleAxisd(angle(t), Eigen::Vector3d::UnitZ());
    return f;
  };
}

struct TorsionResult {
  double torque = 0;        // measured axial torque on the turned end, N m (magnitude)
  double expected = 0;      // G J theta'
  double twist_rate = 0;    // theta', rad/m
  double nonlinearity = 0;  // of theta(z) over the middle 60 %
  int tets = 0;
};

// Quasi-static small twist: 1 s steps make backward Euler a damped Newton iteration on statics.
// Node sets and slices take the body's nodes (for tet10 also the mid-edge ones); J is the
// linear mesh's section (the P2 mesh has the same straight-sided geometry).
struct Protocol {
  double time_step;  // s
  int ramp_steps;    // the end turns linearly over these steps, then holds
  int steps;
};
// 1 s steps, the angle ramped over 3 and held for 9 (the protocol of the tet4 tests below).
constexpr Protocol kRamped{1.0, 3, 12};
// Statics: the slowest mode here is the torsional one, omega = sqrt(G J / (L I_z)) ~ 0.6 rad/s,
// so 1 s steps still carry some dynamics (backward Euler damps it by 0.85 per step). 1000 s steps
// damp every mode by > 500 per step: the angle is applied at once, and each step is a Newton
// step on the statics. 3 steps are statics to the measurement's resolution: a 4th changed the
// torque by < 4e-7 relative and T / (G J theta') by < 4e-7 on every static case of this file
// (tet4 and tet10 on 2430, 4323 and 8332 tets; tet4 at nu up to 0.499, plain and nodal-average;
// 2 steps still left 5e-4), far inside the tightest tolerance asserted (0.5 %), so the checks are
// as strong as with 4 steps (8 steps changed the torque by < 1e-6).
constexpr Protocol kStatic{1000.0, 1, 3};

TorsionResult smallTwist(int tets, double angle, ElementKind element = ElementKind::kTet4,
                         const Protocol& protocol = kRamped, const Material& material = {}) {
  const double ramp = protocol.ramp_steps * protocol.time_step;
  const int steps = protocol.steps;
  const TetMesh linear = cylinder(tets);
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = protocol.time_step;
  settings.solver.linear_solver = LinearSolverKind::kCholmod;
  FemWorld world(settings);
  FemBody* body = world.addBody("cylinder", linear, material, Frame{}, element).value();
  const TetMesh& mesh = body->model().mesh();
  body->carryNodes(
      "base", nodesAtZ(mesh, 0), [](double) { return Frame{}; }, 0);
  const int end = body->carryNodes(
      "end", nodesAtZ(mesh, kLength),
      turnAboutZ([angle, ramp](double t) { return angle * std::min(t / ramp, 1.0); }), 0);
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport r = world.step();
    EXPECT_TRUE(r.ok) << r.message;
  }
  TorsionResult result;
  result.tets = linear.tetCount();
  const auto profile =
      twistProfile(mesh.restPositions(), body->state().positions, sliceCentres(0.5), 0.26);
  result.twist_rate = twistRate(profile, 2, 8);
  result.nonlinearity = twistNonlinearity(profile, 2, 8);
  const double J = polarMomentOfSection(linear.restPositions(), linear.tets(), kLength);
  result.expected = material.mu() * J * result.twist_rate;
  result.torque = -body->groupWrench(end, Eigen::Vector3d(0, 0, kLength)).torque.z();
  return result;
}

// Each twist is solved once per process and shared by the tests that read it (the 8332-tet tet4
// ramp by three, the 8332-tet tet10 statics by two): CTest runs this suite as one test, one
// process (tests/CMakeLists.txt), so every test still asserts on the same solved twist it would
// solve alone, and none is solved twice.
class StVenant : public ::testing::Test {
 protected:
  using Key = std::tuple<int, ElementKind, bool>;
  static std::map<Key, TorsionResult>& results() {
    static std::map<Key, TorsionResult> r;
    return r;
  }
  // The ramped protocol of the tet4 tests, or statics (`is_static`).
  static const TorsionResult& at(int tets, ElementKind element = ElementKind::kTet4,
                                 bool is_static = false) {
    const Key key{tets, element, is_static};
    auto it = results().find(key);
    if (it == results().end()) {
      it = results()
               .emplace(key, smallTwist(tets, 0.05, element, is_static ? kStatic : kRamped))
               .first;
    }
    return it->second;
  }
};

TEST_F(StVenant, SmallTwistIsUniformAlongTheMediumCylinder) {
  const TorsionResult& r = at(8332);
  // Away from the ends the twist is uniform: theta' = total angle / length, theta(z) linear.
  EXPECT_NEAR(r.twist_rate, 0.05 / kLength, 0.02 * 0.05 / kLength);
  EXPECT_LT(r.nonlinearity, 0.01);
}

// Linear tets are too stiff in torsion (the field u = theta' z (-y, x, 0) is bilinear): the torque
// error falls like h^2 with the element size h ~ N^(-1/3). The test asserts that convergence and
// that the h^2 extrapolation of the two finest meshes matches St-Venant within 5 %. The medium
// mesh itself is 15 % stiff (docs/validation.md); the 5 % on 8332 tets is not reached
// with linear tets of this quality.
TEST_F(StVenant, TorqueConvergesToGJThetaPrimeWithRefinement) {
  std::printf("| tets | T (N m) | G J theta' (N m) | T / (G J theta') |\n|---|---|---|---|\n");
  std::vector<std::pair<double, double>> ratios;  // (h^2 ~ N^(-2/3), T / (G J theta'))
  auto csv = test::validationCsv("st_venant_small_twist.csv", "tets,torque,gj_theta_prime,ratio");
  double previous = std::numeric_limits<double>::infinity();
  for (int tets : {2430, 4323, 8332, 31558}) {
    const TorsionResult& r = at(tets);
    const double ratio = r.torque / r.expected;
    std::printf("| %d | %.4f | %.4f | %.4f |\n", r.tets, r.torque, r.expected, ratio);
    if (csv) *csv << r.tets << "," << r.torque << "," << r.expected << "," << ratio << "\n";
    EXPECT_GT(ratio, 1.0) << "linear tets cannot be softer than the continuum";
    EXPECT_LT(ratio, previous) << tets << " tets: refinement must reduce the error";
    previous = ratio;
    ratios.emplace_back(std::pow(double(r.tets), -2.0 / 3.0), ratio);
  }
  // Observed order from the coarsest to the finest mesh: h^p with p near 2.
  const double order = std::log((ratios.front().second - 1) / (ratios.back().second - 1)) /
                       std::log(std::sqrt(ratios.front().first / ratios.back().first));
  const auto [h2_coarse, r_coarse] = ratios[2];
  const auto [h2_fine, r_fine] = ratios[3];
  const double extrapolated = (r_fine * h2_coarse - r_coarse * h2_fine) / (h2_coarse - h2_fine);
  std::printf("observed order %.2f; extrapolated T / (G J theta') = %.4f\n", order, extrapolated);
  EXPECT_GT(order, 1.5);
  EXPECT_NEAR(extrapolated, 1.0, 0.05);
  EXPECT_LT(ratios.back().second, 1.07);  // the fine mesh: within 7 %
}

// Quadratic tets represent the linearly varying shear of torsion: on the same 8332 tets the
// torque is within the 5 % of G J theta' (J of the meshed section), with theta(z) linear.
// Statics (kStatic) for both elements. Measured 1.0004 (tet4 on the same protocol: 1.1506).
TEST_F(StVenant, Tet10SmallTwistTorqueIsGJThetaPrimeWithinFivePercent) {
  const TorsionResult& r = at(8332, ElementKind::kTet10, true);
  const double ratio = r.torque / r.expected;
  std::printf(
      "tet10, 8332 tets: T = %.4f N m, G J theta' = %.4f N m, ratio %.4f, "
      "nonlinearity %.3f %%\n",
      r.torque, r.expected, ratio, 100 * r.nonlinearity);
  EXPECT_NEAR(r.twist_rate, 0.05 / kLength, 0.02 * 0.05 / kLength);
  EXPECT_LT(r.nonlinearity, 0.01);
  EXPECT_NEAR(ratio, 1.0, 0.05);
}

// 2430 -> 4323 -> 8332 tets with tet10 against tet4 on the same meshes and protocol. tet4's error
// falls like h^2 from 34 % to 15 %; tet10 is converged to the resolution of the measurement on
// the coarsest mesh already: every ratio within 1 % of 1 and the three within 0.5 % of each other.
// (The remaining +-0.2 % is the measurement, not the element: the meshed section is a polygon,
// whose torsion constant lies slightly below the polar moment J used here because the section
// warps, and theta' is a fit over slices.) Each mesh is at least 10x closer than tet4.
TEST_F(StVenant, Tet10TorqueIsConvergedWhereTet4IsStillConverging) {
  std::printf("| tets | element | T / (G J theta') |\n|---|---|---|\n");
  auto csv = test::validationCsv("st_venant_tet10.csv", "tets,element,torque,gj_theta_prime,ratio");
  double lowest = std::numeric_limits<double>::infinity(), highest = 0;
  for (int tets : {2430, 4323, 8332}) {
    const TorsionResult& p2 = at(tets, ElementKind::kTet10, true);
    const TorsionResult& p1 = at(tets, ElementKind::kTet4, true);
    const double ratio = p2.torque / p2.expected, linear_ratio = p1.torque / p1.expected;
    std::printf("| %d | tet10 | %.4f |\n| %d | tet4 | %.4f |\n", tets, ratio, tets, linear_ratio);
    if (csv) {
      *csv << tets << ",tet10," << p2.torque << "," << p2.expected << "," << ratio << "\n";
      *csv << tets << ",tet4," << p1.torque << "," << p1.expected << "," << linear_ratio << "\n";
    }
    EXPECT_NEAR(ratio, 1.0, 0.01) << tets << " tets";
    EXPECT_LT(std::abs(ratio - 1), (linear_ratio - 1) / 10) << tets << " tets: tet10 vs tet4";
    EXPECT_LT(p2.nonlinearity, 0.01) << tets << " tets";
    lowest = std::min(lowest, ratio);
    highest = std::max(highest, ratio);
  }
  EXPECT_LT(highest - lowest, 0.005);
}

// Nearly incompressible (docs/validation.md, "Nearly incompressible tet4"): St-Venant's torsion is
// pure shear, so T / (G J theta') must not depend on nu. Statics on 8332 tets. The plain tet4
// locks: its ratio climbs with nu (every tet's volume constraint fights the twist). With the
// nodal-average volumetric strain (fem/nodal_pressure.h) it stays within 2 % of its nu = 0.3
// value at every nu up to 0.499.
TEST(StVenantNearlyIncompressible, NodalPressureTorqueDoesNotDependOnNu) {
  std::printf(
      "| nu | tet4 T / (G J theta') | vs nu = 0.3 | nodal-pressure T / (G J theta') | vs nu = 0.3 "
      "|\n|---|---|---|---|---|\n");
  auto csv = test::validationCsv("st_venant_nearly_incompressible.csv",
                                 "nu,tet4_ratio,nodal_pressure_ratio");
  double base[2] = {0, 0};
  for (double nu : {0.3, 0.45, 0.49, 0.499}) {
    double ratio[2];
    for (int k = 0; k < 2; ++k) {
      Material material;
      material.poisson_ratio = nu;
      material.volumetric_strain =
          k == 0 ? VolumetricStrain::kPerElement : VolumetricStrain::kNodalAverage;
      const TorsionResult r = smallTwist(8332, 0.05, ElementKind::kTet4, kStatic, material);
      ratio[k] = r.torque / r.expected;
      // The locked plain tet4 does not even twist uniformly at nu = 0.499 (2 %).
      if (k == 1) {
        EXPECT_LT(r.nonlinearity, 0.01) << "nu = " << nu;
      }
      if (nu == 0.3) base[k] = ratio[k];
    }
    std::printf("| %.3f | %.4f | %+.1f %% | %.4f | %+.1f %% |\n", nu, ratio[0],
                100 * (ratio[0] / base[0] - 1), ratio[1], 100 * (ratio[1] / base[1] - 1));
    if (csv) *csv << nu << "," << ratio[0] << "," << ratio[1] << "\n";
    EXPECT_NEAR(ratio[1], base[1], 0.02 * base[1]) << "nu = " << nu;
    EXPECT_GT(ratio[1], 1.0) << "a conforming tet is not softer than St-Venant, nu = " << nu;
    if (nu >= 0.49) {
      EXPECT_GT(ratio[0], 1.1 * base[0]) << "the plain tet4 no longer locks at nu = " << nu;
    }
  }
}

// Through the hand plane (docs/design.md section 5): the same small twist, applied by a hand whose
// plane z = 9.9 grabs the ring of surface triangles it cuts (the end cap and the interior stay
// free). The twist is still uniform in the middle, the hand's torque balances the fixed base's,
// and T / (G J theta') is the mesh's own ratio from the end-rotation test above: the hand adds no
// error of its own. That ratio is 1.15 on 8332 tets, not the 5 % (see the convergence
// test and docs/validation.md).
TEST_F(StVenant, SmallTwistThroughAHandMatchesTheEndRotation) {
  const TetMesh mesh = cylinder(8332);
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = 1.0;  // quasi-static, as in smallTwist
  settings.solver.linear_solver = LinearSolverKind::kCholmod;
  FemWorld world(settings);
  Material material;
  FemBody* body = world.addBody("cylinder", mesh, material).value();
  const int base = body->carryNodes(
      "base", nodesAtZ(mesh, 0), [](double) { return Frame{}; }, 0);
  Hand hand(*body);
  Frame frame;
  frame.origin = Eigen::Vector3d(0, 0, 9.9);
  ASSERT_TRUE(hand.grab(frame, 0).ok());
  const double angle = 0.05;
  for (int k = 1; k <= 12; ++k) {
    frame.rotation = Eigen::AngleAxisd(angle * std::min(k / 3.0, 1.0), Eigen::Vector3d::UnitZ());
    EXPECT_TRUE(hand.moveTo(frame).ok());
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
  }
  const auto profile =
      twistProfile(mesh.restPositions(), body->state().positions, sliceCentres(0.5), 0.26);
  const double rate = twistRate(profile, 2, 8);
  const double J = polarMomentOfSection(mesh.restPositions(), mesh.tets(), kLength);
  const double torque = -hand.wrench().torque.z();
  const double base_torque = body->groupWrench(base, Eigen::Vector3d::Zero()).torque.z();
  const double ratio = torque / (material.mu() * J * rate);
  const TorsionResult& end_rotation = at(8332);
  std::printf(
      "through a hand: theta' = %.6f rad/m, T = %.3f N m, base %.3f N m, "
      "T / (G J theta') = %.4f (end rotation: %.4f)\n",
      rate, torque, base_torque, ratio, end_rotation.torque / end_rotation.expected);
  EXPECT_LT(twistNonlinearity(profile, 2, 8), 0.01);
  // The grabbed band reaches from about z = 9.6 to the rim at z = 10: theta' is the angle over
  // the free length, between 0.05 / 10 and 0.05 / 9.6.
  EXPECT_GT(rate, angle / kLength);
  EXPECT_LT(rate, angle / 9.6);
  EXPECT_NEAR(base_torque, torque, 0.01 * torque);  // quasi-static: the torques balance
  EXPECT_NEAR(ratio, end_rotation.torque / end_rotation.expected, 0.01);
  EXPECT_GT(ratio, 1.0);
}

// The report's case (section 6.1.2): the medium cylinder, its base fixed, twisted by 2 pi at
// 0.1 rad/s with dt = 0.01 by a hand at z = 9.9, then held 2 s. It must stay stable, the angle
// linear along the middle 60 %, the twist rate that of the free length.
TEST(StVenantLargeTwist, TwoPiTwistThroughAHandStaysStableAndLinear) {
  const TetMesh mesh = cylinder(8332);
  WorldSettings settings;
  settings.gravity.setZero();
  FemWorld world(settings);
  FemBody* body = world.addBody("cylinder", mesh, Material{}).value();
  body->carryNodes(
      "base", nodesAtZ(mesh, 0), [](double) { return Frame{}; }, 0);
  Hand hand(*body);
  Frame frame;
  frame.origin = Eigen::Vector3d(0, 0, 9.9);
  ASSERT_TRUE(hand.grab(frame, 0).ok());
  const double omega = 0.1, total = 2 * M_PI, dt = settings.solver.time_step;
  const int steps = static_cast<int>(std::ceil(total / omega / dt)) + 200;
  for (int k = 1; k <= steps; ++k) {
    frame.rotation = Eigen::AngleAxisd(std::min(omega * k * dt, total), Eigen::Vector3d::UnitZ());
    EXPECT_TRUE(hand.moveTo(frame).ok());
    const WorldStepReport r = world.step();
    ASSERT_TRUE(r.ok) << r.message;
  }
  const auto profile =
      twistProfile(mesh.restPositions(), body->state().positions, sliceCentres(0.5), 0.26);
  const double rate = twistRate(profile, 2, 8);
  const double nonlinearity = twistNonlinearity(profile, 2, 8);
  std::printf(
      "2 pi twist through a hand: theta' = %.5f rad/m (2 pi / L = %.5f), "
      "nonlinearity %.2f %%\n",
      rate, total / kLength, 100 * nonlinearity);
  if (auto csv = test::validationCsv("st_venant_two_pi_profile.csv", "z,angle,st_venant")) {
    for (const SliceRotation& slice : profile)
      *csv << slice.z << "," << slice.angle << "," << total * slice.z / kLength << "\n";
  }
  EXPECT_LT(nonlinearity, 0.03);
  EXPECT_GT(rate, 0.98 * total / kLength);
  EXPECT_LT(rate, 1.02 * total / 9.6);
}

}  // namespace
}  // namespace torsion
