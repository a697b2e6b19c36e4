// Internal-force rendering against the solver and against beam theory on the 8332-tet cylinder
// (physics label). The haptic torque is the hand's reaction torque from the solver (the same
// internal forces, about the device's origin) and balances the fixed base's. Against
// St-Venant's G J theta' the element is the limit: linear tets on 8332 elements are ~15 %
// stiff in torsion (docs/validation.md), so their ratio is checked at the tolerance the mesh
// supports; quadratic tets (tet10) on the same mesh meet the 5 %.
#include <gtest/gtest.h>

#include "coupling_rig.h"
#include "torsion/analysis/twist_profile.h"

namespace torsion::haptics {
namespace {

struct HapticTwist {
  double haptic = 0;  // torque about the axis rendered to the device, N m
  double beam = 0;    // G J theta', N m
};

// Twist the device by 0.05 rad about the axis, statics, and check the rendered torque against the
// solver's reaction and the fixed base's. A grab step, then 3 steps at the twisted pose: each is a
// Newton step on the statics, and a 4th changed the rendered torque by < 3e-7 relative, the ratio
// to G J theta' by < 3e-7 and left the base's torque balancing the hand's within 4e-7 either way
// (tet4 and tet10), far inside the 1 % and 5 % asserted: as strong a check as with 4.
HapticTwist hapticTwist(ElementKind element) {
  SolverSettings quasi_static;
  quasi_static.time_step = 1000;  // far beyond every mode: each step solves statics
  quasi_static.linear_solver = LinearSolverKind::kCholmod;
  CouplingRig rig(8332, quasi_static, {}, 0, element);
  const double angle = 0.05;  // rad about the axis
  rig.step(device::Pose{});
  for (int k = 0; k < 3; ++k)
    rig.step(displaced(5, angle));

  HapticTwist result;
  const double haptic = rig.coupling->worldWrench().torque.z();
  const Wrench solver = rig.body->groupWrench(rig.hand->group(), rig.coupling->goal().origin);
  EXPECT_NEAR(haptic, solver.torque.z(), 1e-9 * std::abs(haptic));
  EXPECT_NEAR(haptic, rig.hand->wrench().torque.z(), 1e-6 * std::abs(haptic));
  const Wrench base = rig.body->groupWrench(rig.base_group, Eigen::Vector3d::Zero());
  EXPECT_NEAR(haptic, -base.torque.z(), 0.01 * std::abs(haptic));  // statics: they balance
  EXPECT_LT(haptic, 0);                                            // it resists the twist

  const TetMesh& mesh = rig.body->model().mesh();  // all nodes, for the slices
  const TetMesh& linear = cylinderMesh(8332);      // the meshed section, for J
  std::vector<double> slices;
  for (double z = 0; z <= 9.9 + 1e-9; z += 0.5)
    slices.push_back(z);
  const auto profile =
      twistProfile(mesh.restPositions(), rig.body->state().positions, slices, 0.26);
  const double twist_rate = twistRate(profile, 2, 8);
  const double j = polarMomentOfSection(linear.restPositions(), linear.tets(), 10.0);
  result.haptic = -haptic;
  result.beam = rig.body->model().material().mu() * j * twist_rate;
  std::printf("%s: haptic torque %.3f N m, G J theta' %.3f N m, ratio %.4f\n", toString(element),
              result.haptic, result.beam, result.haptic / result.beam);
  return result;
}

TEST(HapticTorque, EqualsTheSolversReactionAndGJThetaPrimeWithinTheMeshError) {
  const HapticTwist twist = hapticTwist(ElementKind::kTet4);
  // Measured 1.151 here, as docs/validation.md finds for this mesh (1.151 with the end face
  // turned): the ratio is the mesh's torsional stiffness error. Allow 1.0..1.25.
  EXPECT_GT(twist.haptic / twist.beam, 1.0);
  EXPECT_LT(twist.haptic / twist.beam, 1.25);
}

TEST(HapticTorque, Tet10BodyRendersGJThetaPrimeWithinFivePercent) {
  // The same rig with quadratic tets: the hand grabs the P2 surface nodes its plane cuts
  // (corners and mid-edge nodes), and the rendered torque is G J theta' within the 5 %
  // (measured 1.0004, as the end-rotation test in st_venant_test.cpp).
  const HapticTwist twist = hapticTwist(ElementKind::kTet10);
  EXPECT_NEAR(twist.haptic / twist.beam, 1.0, 0.05);
}

}  // namespace
}  // namespace torsion::haptics
