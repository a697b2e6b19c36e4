// The shared narrow phase of FEM surface contact (contact/surface_candidates.h): closest points of
// two edges, the edge-edge candidate's normal, gap and weights, the node-triangle candidate with
// its exclusion rule, and the surface edges' folds. Inline geometry, one quirk per test.
#include "torsion/contact/surface_candidates.h"

#include <gtest/gtest.h>

#include <cmath>

namespace torsion {
namespace {

using Edge = std::array<std::array<Eigen::Vector3d, 2>, 2>;  // [start, end][corner]

// Edge along x at height z0 moving to z1, and edge along y at height 0, at rest: they cross over
// the origin, at the middle of both.
Edge alongX(double z0, double z1) {
  return {{{Eigen::Vector3d(-1, 0, z0), Eigen::Vector3d(1, 0, z0)},
           {Eigen::Vector3d(-1, 0, z1), Eigen::Vector3d(1, 0, z1)}}};
}
Edge alongY() {
  return {{{Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 1, 0)},
           {Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 1, 0)}}};
}

CandidateRules rules() {
  CandidateRules r;
  r.margin = 0.05;
  r.max_depth = 0.25;
  r.crease_depth = 1e-3;
  return r;
}

// e's surface faces down (-z), f's up (+z): f's outward minus e's is +z.
Eigen::Vector3d facingUp() {
  return Eigen::Vector3d(0, 0, 2);
}

TEST(SurfaceCandidates, TheClosestPointsOfTwoCrossingEdgesAreTheirMiddlesAtTheirDistance) {
  double u = -1, v = -1, distance = -1;
  ASSERT_TRUE(
      closestPointsOfLines({-1, 0, 0.3}, {1, 0, 0.3}, {0, -1, 0}, {0, 3, 0}, u, v, distance));
  EXPECT_NEAR(u, 0.5, 1e-15);
  EXPECT_NEAR(v, 0.25, 1e-15);
  EXPECT_NEAR(distance, 0.3, 1e-15);
}

TEST(SurfaceCandidates, ParallelAndZeroLengthEdgesHaveNoClosestPoints) {
  double u = 7, v = 7, distance = 7;
  EXPECT_FALSE(closestPointsOfLines({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 1, 0}, u, v, distance));
  EXPECT_FALSE(closestPointsOfLines({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {2, 1, 0}, u, v, distance));
  EXPECT_EQ(u, 7);  // untouched
  EXPECT_EQ(distance, 7);
}

TEST(SurfaceCandidates, AnEdgePassingThroughAnotherOnThePathIsACandidateWithWeightsAtTheCrossing) {
  // From 0.2 above to 0.2 below in one step: the crossing is at s = 0.5, over the middles.
  const std::optional<EdgeEdgeHit> hit =
      edgeEdgeCandidate(alongX(0.2, -0.2), alongY(), rules(), {}, facingUp, {});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->normal.z(), 1, 1e-15);  // out of f's surface into e's
  EXPECT_NEAR(hit->gap, 0.2, 1e-15);
  EXPECT_NEAR(hit->u, 0.5, 1e-12);
  EXPECT_NEAR(hit->v, 0.5, 1e-12);
  // beta = (1 - u, u, -(1 - v), -v): equal and opposite impulses on the two edges.
  EXPECT_NEAR((1 - hit->u) + hit->u - (1 - hit->v) - hit->v, 0, 1e-15);
}

TEST(SurfaceCandidates, TheEdgePairsNormalFollowsTheSurfacesNotTheOrderOfTheCorners) {
  // The same pair with e's corners swapped: e x f flips, the oriented normal does not.
  Edge swapped = alongX(0.02, 0.02);
  std::swap(swapped[0][0], swapped[0][1]);
  std::swap(swapped[1][0], swapped[1][1]);
  const std::optional<EdgeEdgeHit> a =
      edgeEdgeCandidate(alongX(0.02, 0.02), alongY(), rules(), {}, facingUp, {});
  const std::optional<EdgeEdgeHit> b =
      edgeEdgeCandidate(swapped, alongY(), rules(), {}, facingUp, {});
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(a->normal.z(), 1, 1e-15);
  EXPECT_NEAR(b->normal.z(), 1, 1e-15);
  EXPECT_NEAR(a->gap, 0.02, 1e-15);
  EXPECT_NEAR(b->gap, 0.02, 1e-15);
  EXPECT_NEAR(b->u, 1 - a->u, 1e-15);
}

TEST(SurfaceCandidates, ParallelDegenerateDistantAndAvertedEdgePairsAreNoCandidates) {
  const auto none = [](const Edge& e, const Edge& f, const std::function<Eigen::Vector3d()>& out) {
    return !edgeEdgeCandidate(e, f, rules(), {}, out, {}).has_value();
  };
  // Parallel: nodes and faces hold them.
  const Edge parallel = {{{Eigen::Vector3d(-1, 0.1, 0.01), Eigen::Vector3d(1, 0.1, 0.01)},
                          {Eigen::Vector3d(-1, 0.1, 0.01), Eigen::Vector3d(1, 0.1, 0.01)}}};
  EXPECT_TRUE(none(alongX(0.01, 0.01), parallel, facingUp));
  // Zero length.
  const Edge point = {{{Eigen::Vector3d(0, 0, 0.01), Eigen::Vector3d(0, 0, 0.01)},
                       {Eigen::Vector3d(0, 0, 0.01), Eigen::Vector3d(0, 0, 0.01)}}};
  EXPECT_TRUE(none(point, alongY(), facingUp));
  // Apart all along the path (beyond the margin).
  EXPECT_TRUE(none(alongX(0.5, 0.3), alongY(), facingUp));
  // Lines crossing beyond the ends of the edges.
  const Edge beside = {{{Eigen::Vector3d(2, 0, 0.01), Eigen::Vector3d(3, 0, 0.01)},
                        {Eigen::Vector3d(2, 0, 0.01), Eigen::Vector3d(3, 0, 0.01)}}};
  EXPECT_TRUE(none(beside, alongY(), facingUp));
  // Surfaces not facing each other (outward normals along the edges' plane).
  EXPECT_TRUE(none(alongX(0.01, 0.01), alongY(), [] { return Eigen::Vector3d(2, 0, 0); }));
}

TEST(SurfaceCandidates, ACrossedEdgePairIsRefusedUnlessHeldAndThenKeepsItsSide) {
  // e starts 5 mm below f although its surface faces down onto f: crossed before the step.
  EXPECT_FALSE(edgeEdgeCandidate(alongX(-0.005, -0.005), alongY(), rules(), {}, facingUp, {}));
  // Held last step pushing e up: the pair stays, with its normal up and a negative gap.
  const Eigen::Vector3d pushed_up(0, 0, 0.3);
  const std::optional<EdgeEdgeHit> held = edgeEdgeCandidate(
      alongX(-0.005, -0.005), alongY(), rules(), [&] { return &pushed_up; }, facingUp, {});
  ASSERT_TRUE(held);
  EXPECT_NEAR(held->normal.z(), 1, 1e-15);
  EXPECT_NEAR(held->gap, -0.005, 1e-15);
}

TEST(SurfaceCandidates, TheCallersExclusionRuleRefusesOnlyNewPairs) {
  const ExclusionRule all = [](const Eigen::Vector3d&, double) { return true; };
  EXPECT_FALSE(edgeEdgeCandidate(alongX(0.01, 0.01), alongY(), rules(), {}, facingUp, all));
  const Eigen::Vector3d pushed_up(0, 0, 0.3);
  EXPECT_TRUE(edgeEdgeCandidate(
      alongX(0.01, 0.01), alongY(), rules(), [&] { return &pushed_up; }, facingUp, all));
  // Node against triangle, the same way.
  const std::array<Eigen::Vector3d, 3> triangle = {
      Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)};
  const std::array<Eigen::Vector3d, 2> node = {Eigen::Vector3d(0.2, 0.3, 0.01),
                                               Eigen::Vector3d(0.2, 0.3, 0.01)};
  EXPECT_FALSE(nodeTriangleCandidate(node, triangle, triangle, rules(), false, all));
  EXPECT_TRUE(nodeTriangleCandidate(node, triangle, triangle, rules(), true, all));
}

TEST(SurfaceCandidates, ANodeCrossingATriangleIsJudgedWhereItMeetsThePlane) {
  const std::array<Eigen::Vector3d, 3> triangle = {
      Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)};
  // From (0.9, 0.3, 0.3) to (-0.1, 0.3, -0.1): meets the plane at s = 0.75, at (0.15, 0.3, 0).
  const std::optional<NodeTriangleHit> hit =
      nodeTriangleCandidate({Eigen::Vector3d(0.9, 0.3, 0.3), Eigen::Vector3d(-0.1, 0.3, -0.1)},
                            triangle, triangle, rules(), false, {});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->when, 0.75, 1e-15);
  EXPECT_NEAR(hit->gap, 0.3, 1e-15);
  EXPECT_NEAR(hit->weights[1], 0.15, 1e-12);
  EXPECT_NEAR(hit->weights[2], 0.3, 1e-12);
  // At the start over (0.9, 0.3): outside; only the crossing's projection counts.
  // A node that ends beside the triangle, never over it: none.
  EXPECT_FALSE(
      nodeTriangleCandidate({Eigen::Vector3d(1.5, 0.3, 0.3), Eigen::Vector3d(1.2, 0.3, -0.1)},
                            triangle, triangle, rules(), false, {}));
}

TEST(SurfaceCandidates, SurfaceEdgesKnowTheirTrianglesAndHowFarTheyFold) {
  // Two triangles on edge (0, 1): flat, then folded to a right angle.
  const std::vector<Triangle> triangles = {{0, 1, 2}, {1, 0, 3}};
  const SurfaceEdges edges(triangles);
  ASSERT_EQ(edges.edges.size(), 5u);
  EXPECT_EQ(edges.edges[0], (std::array<int, 2>{0, 1}));
  EXPECT_EQ(edges.edge_triangles[0], (std::array<int, 2>{0, 1}));
  EXPECT_EQ(edges.edge_triangles[1][1], -1);  // (0, 2): one triangle
  Eigen::VectorXd x(12);
  x << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, -1, 0;
  EXPECT_NEAR(edges.foldCosine(0, triangles, x), 1, 1e-15);
  EXPECT_NEAR(edges.outwardNormal(0, triangles, x).z(), 1, 1e-15);
  x.segment<3>(9) = Eigen::Vector3d(0, 0, -1);
  EXPECT_NEAR(edges.foldCosine(0, triangles, x), 0, 1e-15);
  EXPECT_EQ(edges.foldCosine(1, triangles, x), -1);
}

}  // namespace
}  // namespace torsion
