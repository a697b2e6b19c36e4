// A body renumbered for cache locality (NodeNumbering::kCacheFriendly) is the same body as one
// that keeps its mesh's numbers: its input numbering maps every node, tet and element back, the
// input-numbered state follows the state, and the motion agrees to rounding.
#include <gtest/gtest.h>

#include <algorithm>

#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/mesh/node_ordering.h"
#include "user_world.h"

namespace torsion {
namespace {

using testing::UserWorld;

// A 1 x 0.2 x 0.2 m bar whose nodes are scattered as a mesher's insertion order leaves them: node
// i moves to i * 37 mod n (37 is prime and does not divide n = 11 * 3 * 3 = 99).
TetMesh scatteredBar() {
  const TetMesh bar = makeBoxTetMesh({0, 0, 0}, {1, 0.2, 0.2}, 10, 2, 2).value();
  const int n = bar.nodeCount();
  std::vector<int> scatter(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    scatter[static_cast<size_t>(i)] = (i * 37) % n;
  return renumberNodes(bar, scatter);
}

// The nodes of `body` at x = 0 (its own numbers).
std::vector<int> clampedEnd(const FemBody& body) {
  std::vector<int> nodes;
  const auto& rest = body.model().mesh().restPositions();
  for (int i = 0; i < body.model().nodeCount(); ++i)
    if (rest[static_cast<size_t>(i)].x() < 1e-9) nodes.push_back(i);
  return nodes;
}

TEST(InputNumbering, OnlyAMeshWhoseTetsSpreadTheirNumbersIsRenumbered) {
  // A mesh already in that order (as every mesh Torsion writes) is left as it is.
  const TetMesh scattered = scatteredBar();
  EXPECT_FALSE(cacheFriendlyRenumbering(inCacheFriendlyOrder(scattered)).has_value());
  const std::optional<RenumberedMesh> renumbered = cacheFriendlyRenumbering(scattered);
  ASSERT_TRUE(renumbered.has_value());
  EXPECT_LE(2 * meanTetIndexSpan(renumbered->mesh), meanTetIndexSpan(scattered));
}

class RenumberedBody : public ::testing::TestWithParam<ElementKind> {};

TEST_P(RenumberedBody, IsTheSameBodyInTheMeshsNumbersAndMovesAsItToRounding) {
  const TetMesh mesh = scatteredBar();
  UserWorld as_given_world, renumbered_world;
  FemBody& as_given =
      *as_given_world.fem.addBody("bar", mesh, Material{}, {}, GetParam(), NodeNumbering::kAsGiven)
           .value();
  FemBody& renumbered =
      *renumbered_world.fem
           .addBody("bar", mesh, Material{}, {}, GetParam(), NodeNumbering::kCacheFriendly)
           .value();
  EXPECT_TRUE(as_given.inputNumbering().identity());
  const InputNumbering& numbering = renumbered.inputNumbering();
  ASSERT_FALSE(numbering.identity());

  // The input-numbered mesh is the as-given body's mesh, bit for bit (tet10: mid-edge nodes and
  // sub-tets included), and the elements map to its elements.
  const TetMesh& input = *numbering.inputMesh();
  EXPECT_EQ(input.restPositions(), as_given.model().mesh().restPositions());
  EXPECT_EQ(input.tets(), as_given.model().mesh().tets());
  const FemModel& model = renumbered.model();
  const int per = model.nodesPerElement();
  const int tets_per_element = model.mesh().tetCount() / model.elementCount();
  for (int c = 0; c < model.elementCount(); ++c) {
    const int e = numbering.bodyElement(c, tets_per_element);
    EXPECT_EQ(numbering.inputElement(e, tets_per_element), c);
    for (int a = 0; a < per; ++a)
      ASSERT_EQ(numbering.inputNode(model.elementNodes()[static_cast<size_t>(per * e + a)]),
                as_given.model().elementNodes()[static_cast<size_t>(per * c + a)]);
  }
  for (int i = 0; i < model.nodeCount(); ++i)
    EXPECT_EQ(numbering.bodyNode(numbering.inputNode(i)), i);

  // Clamped at x = 0, sagging under gravity for 30 steps: the same motion, up to the rounding of
  // sums taken in another order (bounded at 1e-9 of the 5 cm sag).
  const FrameMotion held([](double) { return Frame{}; });
  as_given.carryNodes("clamp", clampedEnd(as_given), held, 0.0);
  renumbered.carryNodes("clamp", clampedEnd(renumbered), held, 0.0);
  const auto dt = static_cast<btScalar>(0.01);
  for (int k = 0; k < 30; ++k) {
    as_given_world.world.stepSimulation(dt, 0);
    renumbered_world.world.stepSimulation(dt, 0);
  }
  ASSERT_TRUE(as_given_world.fem.status().ok) << as_given_world.fem.status().message;
  ASSERT_TRUE(renumbered_world.fem.status().ok) << renumbered_world.fem.status().message;
  const Eigen::VectorXd& expected = as_given.state().positions;
  const auto& rest = as_given.model().mesh().restPositions();
  const double sag =
      (expected - Eigen::Map<const Eigen::VectorXd>(rest.front().data(), expected.size()))
          .lpNorm<Eigen::Infinity>();
  ASSERT_GT(sag, 1e-3);
  EXPECT_LT((renumbered.inputPositions() - expected).lpNorm<Eigen::Infinity>(), 1e-9 * sag);
  EXPECT_LT((renumbered.inputVelocities() - as_given.state().velocities).lpNorm<Eigen::Infinity>(),
            1e-9 * sag / 0.3);
  // The input-numbered state is the body's own, permuted, and keeps its address.
  EXPECT_EQ(renumbered.inputPositions(), numbering.nodesToInput(renumbered.state().positions));
  const double* address = renumbered.inputPositions().data();
  ASSERT_TRUE(renumbered.setVelocity(Eigen::Vector3d(0, 0, 1)).ok());
  EXPECT_EQ(renumbered.inputPositions().data(), address);
  EXPECT_EQ(renumbered.inputVelocities(), numbering.nodesToInput(renumbered.state().velocities));
}

INSTANTIATE_TEST_SUITE_P(Elements, RenumberedBody,
                         ::testing::Values(ElementKind::kTet4, ElementKind::kTet10),
                         [](const ::testing::TestParamInfo<ElementKind>& element) {
                           return element.param == ElementKind::kTet4 ? "Tet4" : "Tet10";
                         });

}  // namespace
}  // namespace torsion
