// Internal-force rendering against the solver and against beam theory on the 8332-tet cylinder
// (physics label). The haptic torque is the hand's reaction torque from the solver (the same
// internal forces, about the device's origin) and balances the fixed base's. Against
// St-Venant's G J theta' the mesh itself is the limit: linear tets on 8332 elements are ~15 %
// stiff in torsion (docs/validation.md), so the ratio is checked at the tolerance the mesh
// supports, not at 5 %.
#include <gtest/gtest.h>

#include "coupling_rig.h"
#include "torsion/analysis/twist_profile.h"

namespace torsion::haptics {
namespace {

TEST(HapticTorque, EqualsTheSolversReactionAndGJThetaPrimeWithinTheMeshError) {
  SolverSettings quasi_static;
  quasi_static.time_step = 1000;  // far beyond every mode: each step solves statics
  quasi_static.linear_solver = LinearSolverKind::kCholmod;
  CouplingRig rig(8332, quasi_static);
  const double angle = 0.05;  // rad about the axis
  rig.step(device::Pose{});
  for (int k = 0; k < 4; ++k)
    rig.step(displaced(5, angle));

  const double haptic = rig.coupling->worldWrench().torque.z();
  const Wrench solver = rig.body->groupWrench(rig.hand->group(), rig.coupling->goal().origin);
  EXPECT_NEAR(haptic, solver.torque.z(), 1e-9 * std::abs(haptic));
  EXPECT_NEAR(haptic, rig.hand->wrench().torque.z(), 1e-6 * std::abs(haptic));
  const Wrench base = rig.body->groupWrench(rig.base_group, Eigen::Vector3d::Zero());
  EXPECT_NEAR(haptic, -base.torque.z(), 0.01 * std::abs(haptic));  // statics: they balance
  EXPECT_LT(haptic, 0);                                            // it resists the twist

  const TetMesh& mesh = cylinderMesh(8332);
  std::vector<double> slices;
  for (double z = 0; z <= 9.9 + 1e-9; z += 0.5)
    slices.push_back(z);
  const auto profile =
      twistProfile(mesh.restPositions(), rig.body->state().positions, slices, 0.26);
  const double twist_rate = twistRate(profile, 2, 8);
  const double j = polarMomentOfSection(mesh.restPositions(), mesh.tets(), 10.0);
  const double beam = rig.body->model().material().mu() * j * twist_rate;
  const double ratio = -haptic / beam;
  std::printf("haptic torque %.3f N m, G J theta' %.3f N m, ratio %.4f\n", -haptic, beam, ratio);
  // Measured 1.151 here, as docs/validation.md finds for this mesh (1.151 with the end face
  // turned): the ratio is the mesh's torsional stiffness error. Allow 1.0..1.25.
  EXPECT_GT(ratio, 1.0);
  EXPECT_LT(ratio, 1.25);
}

}  // namespace
}  // namespace torsion::haptics
