// The stress the pictures colour by (frame_data.h, tetVonMises): for a hyperelastic body it is its
// law's Cauchy stress, so a body turned rigidly shows none (its element rotations, which the
// corotated display needs, are never set for it), and a small stretch shows the corotated value.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "frame_data.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion::render {
namespace {

// The body's von Mises stress with its nodes moved to x -> A x (no step taken).
std::vector<double> stressUnder(MaterialLaw law, const Eigen::Matrix3d& A) {
  FemWorld world{WorldSettings{}};
  Material material;
  material.law = law;
  const TetMesh mesh =
      makeBoxTetMesh(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 1, 1), 2, 2, 2).value();
  FemBody* body = world.addBody("block", mesh, material).value();
  FemBodyCheckpoint moved = body->checkpoint();
  for (int i = 0; i < mesh.nodeCount(); ++i)
    moved.state.positions.segment<3>(3 * i) = A * moved.state.position(i);
  body->restore(moved);
  return tetVonMises(*body);
}

TEST(StressDisplay, HyperelasticBodyTurnedRigidlyShowsNoStress) {
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(1.2, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (MaterialLaw law : {MaterialLaw::kStableNeoHookean, MaterialLaw::kMooneyRivlin}) {
    const std::vector<double> stress = stressUnder(law, turn);
    EXPECT_LT(*std::max_element(stress.begin(), stress.end()), 1e-9 * Material{}.youngs_modulus)
        << toString(law);
  }
}

// A 0.1 % stretch: the laws are linear elasticity to first order (relative difference O(strain)).
TEST(StressDisplay, HyperelasticStressIsTheCorotatedOneAtSmallStrain) {
  const Eigen::Matrix3d stretch = Eigen::Vector3d(1.001, 1, 1).asDiagonal();
  const std::vector<double> corotated = stressUnder(MaterialLaw::kCorotated, stretch);
  for (MaterialLaw law : {MaterialLaw::kStableNeoHookean, MaterialLaw::kMooneyRivlin}) {
    const std::vector<double> stress = stressUnder(law, stretch);
    for (size_t t = 0; t < stress.size(); ++t)
      EXPECT_NEAR(stress[t], corotated[t], 1e-2 * corotated[t]) << toString(law) << ", tet " << t;
  }
}

}  // namespace
}  // namespace torsion::render
