// The factored exact Hessian of a linear tet (fem/factored_tet_hessian.h): for the stable
// neo-Hookean law it is the exact Hessian the tangent's eigensystem builds (hyperelastic.h), at
// rest, stretched, sheared and inverted, and with the volume barrier's J terms added it is that
// Hessian plus the barrier's (volume_barrier.h); each block is symmetric to its mirror.
#include "torsion/fem/factored_tet_hessian.h"

#include <gtest/gtest.h>

#include "torsion/fem/corotated_element.h"
#include "torsion/fem/hyperelastic.h"

namespace torsion::factored_tet_hessian_test {

using Nodes = std::array<Eigen::Vector3d, 4>;

const Nodes kRest = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0.1, 0),
                     Eigen::Vector3d(0.2, 0.9, 0.1), Eigen::Vector3d(0.1, 0.2, 1.1)};

std::vector<Nodes> shapes() {
  Nodes stretched = kRest, sheared = kRest, inverted = kRest, flat = kRest;
  stretched[1] += Eigen::Vector3d(0.4, -0.1, 0.2);
  stretched[3] += Eigen::Vector3d(-0.2, 0.3, 0.3);
  sheared[3] += Eigen::Vector3d(0.8, -0.3, 0.0);
  inverted[3] = Eigen::Vector3d(0.2, 0.3, -0.4);  // through face (0, 1, 2)
  flat[3] = Eigen::Vector3d(0.4, 0.3, 0.05);      // nearly in face (0, 1, 2)
  return {kRest, stretched, sheared, inverted, flat};
}

TEST(FactoredTetHessian, IsTheStableNeoHookeanExactHessian) {
  const TetRestData rest = tetRestData(kRest);
  const std::array<Eigen::Vector3d, 4> g = shapeGradients(rest.rest_shape_inverse);
  for (double nu : {0.3, 0.45, 0.499}) {
    const StableNeoHookean law = StableNeoHookean::fromYoungPoisson(1e5, nu);
    for (const Nodes& x : shapes()) {
      const Eigen::Matrix3d F = deformationGradient(x, rest.rest_shape_inverse);
      const double J = F.determinant();
      const TetStiffness expected =
          hyperelasticTet(law, x, rest, TetStiffnessKind::kExact).exact_stiffness;
      const TetStiffness factored = expandFactoredHessian(
          factoredTetHessian(F, g, rest.volume, law.lambda, law.lambda * (J - law.alpha)), g,
          law.mu * rest.volume);
      // The two sum the same terms in different orders: rounding of the largest entries.
      EXPECT_LE((factored - expected).norm(), 1e-12 * expected.norm()) << "nu " << nu;
      EXPECT_EQ(factored, factored.transpose());
    }
  }
}

TEST(FactoredTetHessian, AddsTheVolumeBarrierAsItsJTerms) {
  const TetRestData rest = tetRestData(kRest);
  const std::array<Eigen::Vector3d, 4> g = shapeGradients(rest.rest_shape_inverse);
  const StableNeoHookean law = StableNeoHookean::fromYoungPoisson(1e5, 0.3);
  const VolumeBarrier barrier{0.5, 3e5};
  const Nodes inverted = shapes()[3];
  const Eigen::Matrix3d F = deformationGradient(inverted, rest.rest_shape_inverse);
  const double J = F.determinant();
  ASSERT_TRUE(barrier.active(J));
  const TetStiffness expected =
      hyperelasticTet(law, inverted, rest, TetStiffnessKind::kExact).exact_stiffness +
      volumeBarrierHessian(F, rest, barrier);
  const TetStiffness factored = expandFactoredHessian(
      factoredTetHessian(F, g, rest.volume, law.lambda + barrier.densitySecondDerivative(J),
                         law.lambda * (J - law.alpha) + barrier.densityDerivative(J)),
      g, law.mu * rest.volume);
  EXPECT_LE((factored - expected).norm(), 1e-12 * expected.norm());
}

TEST(FactoredTetHessian, PairIndicesCoverTheSixPairs) {
  std::array<int, 6> seen{};
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      ++seen[static_cast<size_t>(nodePairIndex(a, b))];
  for (int count : seen)
    EXPECT_EQ(count, 1);
}

}  // namespace torsion::factored_tet_hessian_test
