// The system operator's two kernel builds (baseline and AVX2 + FMA, system_operator.h): the same
// K and the same products to rounding, for tet4 and tet10; and the tet4 blocks against the
// element's own force differential. (The tet10 blocks are checked against the element
// differentials in quadratic_mesh_test.cpp.)

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstring>
#include <random>

#include "torsion/fem/corotated_element.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/solve/system_operator.h"

namespace torsion {
namespace {

std::shared_ptr<const FemModel> beam(ElementKind element) {
  auto mesh = std::make_shared<const TetMesh>(
      makeBoxTetMesh(Eigen::Vector3d::Zero(), {4, 1, 1}, 4, 2, 2).value());
  return FemModel::create(mesh, Material{}, element).value();
}

void randomRotations(SystemOperator& op, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  for (auto& R : op.mutableRotations())
    R = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

Eigen::VectorXd randomVector(int size, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::VectorXd y(size);
  for (int i = 0; i < size; ++i)
    y[i] = n(rng);
  return y;
}

// Products and blocks of both builds for one model; on a CPU without AVX2 both runs are the
// baseline build and agree exactly.
void expectBuildsAgree(ElementKind element) {
  auto model = beam(element);
  Parallel parallel(1);
  SystemOperator best(model, parallel), baseline(model, parallel);
  baseline.useBaselineKernels(true);
  EXPECT_STREQ(baseline.kernelPath(), "sse2");
  EXPECT_STREQ(best.kernelPath(), SystemOperator::bestKernelPath());
  std::mt19937 rng(3);
  randomRotations(best, rng);
  baseline.mutableRotations() = best.rotations();
  best.setCoefficients(1.01, 1e-4);
  baseline.setCoefficients(1.01, 1e-4);
  const Eigen::VectorXd y = randomVector(3 * model->nodeCount(), rng);
  Eigen::VectorXd a, b;
  best.multiply(y, a);
  baseline.multiply(y, b);
  EXPECT_LT((a - b).norm(), 1e-13 * b.norm());
  const auto& blocks_a = best.stiffnessBlocks();
  const auto& blocks_b = baseline.stiffnessBlocks();
  ASSERT_EQ(blocks_a.size(), blocks_b.size());
  double largest = 0, difference = 0;
  for (size_t s = 0; s < blocks_a.size(); ++s) {
    largest = std::max(largest, blocks_b[s].cwiseAbs().maxCoeff());
    difference = std::max(difference, (blocks_a[s] - blocks_b[s]).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(difference, 1e-13 * largest);
}

TEST(SystemOperatorKernels, BothBuildsGiveTheSameTet4MatrixAndProducts) {
  expectBuildsAgree(ElementKind::kTet4);
}

TEST(SystemOperatorKernels, BothBuildsGiveTheSameTet10MatrixAndProducts) {
  expectBuildsAgree(ElementKind::kTet10);
}

// K y from the blocks equals minus the sum of the elements' force differentials, for each build.
TEST(SystemOperatorKernels, Tet4ProductsMatchTheElementDifferentialsInEitherBuild) {
  auto model = beam(ElementKind::kTet4);
  Parallel parallel(2);
  for (bool baseline : {false, true}) {
    SystemOperator op(model, parallel);
    op.useBaselineKernels(baseline);
    std::mt19937 rng(11);
    randomRotations(op, rng);
    const Eigen::VectorXd y = randomVector(3 * model->nodeCount(), rng);
    Eigen::VectorXd reference = Eigen::VectorXd::Zero(y.size());
    const double mu = model->material().mu(), lambda = model->material().lambda();
    for (int e = 0; e < model->elementCount(); ++e) {
      const int* nodes = model->elementNodes().data() + 4 * e;
      std::array<Eigen::Vector3d, 4> dx;
      for (size_t a = 0; a < 4; ++a)
        dx[a] = y.segment<3>(3 * nodes[a]);
      const auto df =
          corotatedForceDifferential(dx, op.rotations()[static_cast<size_t>(e)],
                                     model->tetRestData()[static_cast<size_t>(e)], mu, lambda);
      for (size_t a = 0; a < 4; ++a)
        reference.segment<3>(3 * nodes[a]) -= df[a];
    }
    Eigen::VectorXd Ky;
    op.multiplyStiffness(y, Ky);
    EXPECT_LT((Ky - reference).norm(), 1e-12 * reference.norm()) << op.kernelPath();
  }
}

}  // namespace
}  // namespace torsion
