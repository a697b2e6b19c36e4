// Exact orientation predicates and the surface-intersection checker
// (analysis/exact_predicates.h, analysis/surface_intersections.h): hand-made triangles that cross,
// touch, miss by one rounding step, lie in one plane, or share corners; meshes at rest and pushed
// through themselves or each other.
#include "torsion/analysis/surface_intersections.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "torsion/analysis/exact_predicates.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

using V = Eigen::Vector3d;

TEST(Orient2dSign, IsExactWherePlainDoublesGuess) {
  // Kettner et al.'s classroom example: points within a few ulps of the line y = x, where the
  // determinant evaluated in double returns signs at random. Exactly: 12 (py - px).
  const double ulp = std::ldexp(1.0, -53);
  const Eigen::Vector2d q(12, 12), r(24, 24);
  for (int i = 0; i < 32; ++i)
    for (int j = 0; j < 32; ++j) {
      const Eigen::Vector2d p(0.5 + i * ulp, 0.5 + j * ulp);
      EXPECT_EQ(orient2dSign(p, q, r), (j > i) - (j < i)) << "i " << i << " j " << j;
    }
}

TEST(Orient3dSign, ZeroOnThePlaneAndTheSignOfOneUlpOffIt) {
  // The plane z = 0.5 x + 0.25 y + 0.125, far from the origin so that differences round; its
  // normal (b - a) x (c - a) points to +z.
  const V o(1e6, -3e5, 7e5);
  const V a = o + V(0, 0, 0.125), b = o + V(1, 0, 0.625), c = o + V(0, 1, 0.375);
  const V on = o + V(3, 5, 2.875);
  EXPECT_EQ(orient3dSign(a, b, c, on), 0);
  V above = on, below = on;
  above.z() = std::nextafter(on.z(), std::numeric_limits<double>::infinity());
  below.z() = std::nextafter(on.z(), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(orient3dSign(a, b, c, above), -1);
  EXPECT_EQ(orient3dSign(a, b, c, below), 1);
  // Far from the plane the fast path answers, with the same convention.
  EXPECT_EQ(orient3dSign(a, b, c, o + V(0, 0, 10)), -1);
  EXPECT_EQ(orient3dSign(V(0, 0, 0), V(1, 0, 0), V(0, 1, 0), V(0, 0, -1)), 1);
}

// P: the right triangle in the plane z = 1 with legs 2 along x and y.
const TriangleCorners kP{V(0, 0, 1), V(2, 0, 1), V(0, 2, 1)};

TriangleCorners shifted(const TriangleCorners& t, const V& by) {
  return {t[0] + by, t[1] + by, t[2] + by};
}

TEST(TrianglesIntersect, CrossingTrianglesIntersectAndSeparatedOnesDoNot) {
  const TriangleCorners piercing{V(0.5, 0.5, 0), V(0.6, 0.5, 2), V(0.5, 0.6, 2)};
  EXPECT_TRUE(trianglesIntersect(kP, piercing));
  EXPECT_TRUE(trianglesIntersect(piercing, kP));
  EXPECT_FALSE(trianglesIntersect(kP, shifted(piercing, V(0, 0, 1.5))));
  // Straddling P's plane but beside P: no edge of either meets the other.
  EXPECT_FALSE(trianglesIntersect(kP, shifted(piercing, V(2, 2, 0))));
  // Through P's plane inside P's box but outside its hypotenuse.
  EXPECT_FALSE(trianglesIntersect(kP, shifted(piercing, V(1.0, 1.0, 0))));
}

TEST(TrianglesIntersect, TouchingCountsAndOneUlpAwayDoesNot) {
  // A corner of Q on P's face.
  const TriangleCorners corner_on{V(0.5, 0.5, 1), V(1, 1, 2), V(0, 1, 2)};
  EXPECT_TRUE(trianglesIntersect(kP, corner_on));
  TriangleCorners lifted = corner_on;
  lifted[0].z() = std::nextafter(1.0, 2.0);
  EXPECT_FALSE(trianglesIntersect(kP, lifted));
  // A corner of Q on P's hypotenuse (x + y = 2), Q otherwise above.
  const TriangleCorners on_edge{V(1, 1, 1), V(1, 1, 2), V(2, 2, 2)};
  EXPECT_TRUE(trianglesIntersect(kP, on_edge));
  // An edge of Q crossing P's edge along x at (1, 0, 1), Q otherwise on the far side (y < 0).
  const TriangleCorners edge_across{V(1, -1, 0), V(1, 1, 2), V(1, -1, 2)};
  EXPECT_TRUE(trianglesIntersect(kP, edge_across));
  EXPECT_FALSE(trianglesIntersect(kP, shifted(edge_across, V(0, -1e-12, 0))));
}

TEST(TrianglesIntersect, CoplanarOverlapsTouchesAndGaps) {
  EXPECT_TRUE(trianglesIntersect(kP, shifted(kP, V(0.5, 0.5, 0))));  // overlapping
  const TriangleCorners inside{V(0.2, 0.2, 1), V(0.5, 0.2, 1), V(0.2, 0.5, 1)};
  EXPECT_TRUE(trianglesIntersect(kP, inside));  // no edges cross: one contains the other
  EXPECT_TRUE(trianglesIntersect(inside, kP));
  // Mirrored through P's corner (2, 0): the two touch at that corner only.
  const TriangleCorners mirrored{V(4, 0, 1), V(2, 0, 1), V(4, -2, 1)};
  EXPECT_TRUE(trianglesIntersect(kP, mirrored));
  EXPECT_FALSE(trianglesIntersect(kP, shifted(mirrored, V(1e-12, 0, 0))));
  EXPECT_FALSE(trianglesIntersect(kP, shifted(kP, V(3, 0, 0))));  // apart in the plane
  // A zero-area triangle (a segment) lying across P in its plane, and beside it.
  const TriangleCorners needle{V(-1, 0.5, 1), V(1, 0.5, 1), V(3, 0.5, 1)};
  EXPECT_TRUE(trianglesIntersect(kP, needle));
  EXPECT_FALSE(trianglesIntersect(kP, shifted(needle, V(0, 5, 0))));
}

// A strip of four triangles: only the first and the last share no corner.
// A segment through the triangle, ending on it, lying in its plane across it, beside it, and a
// zero-area triangle (meets nothing).
TEST(SegmentMeetsTriangle, ThroughOnAndInThePlaneMeetBesideAndDegenerateDoNot) {
  const TriangleCorners t = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                             Eigen::Vector3d(0, 1, 0)};
  EXPECT_TRUE(segmentMeetsTriangle({0.2, 0.2, -1}, {0.2, 0.2, 1}, t));
  EXPECT_TRUE(segmentMeetsTriangle({0.2, 0.2, 1}, {0.2, 0.2, 0}, t));
  EXPECT_TRUE(segmentMeetsTriangle({-1, 0.2, 0}, {2, 0.2, 0}, t));
  EXPECT_FALSE(segmentMeetsTriangle({0.8, 0.8, -1}, {0.8, 0.8, 1}, t));
  EXPECT_FALSE(segmentMeetsTriangle({0.2, 0.2, 1e-12}, {0.2, 0.2, 1}, t));
  const TriangleCorners flat = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0),
                                Eigen::Vector3d(2, 0, 0)};
  EXPECT_FALSE(segmentMeetsTriangle({0.5, 0, -1}, {0.5, 0, 1}, flat));
}

TEST(FindSurfaceIntersections, SkipsTrianglesThatShareACornerAndFindsCrossings) {
  const std::vector<Triangle> triangles{{0, 1, 2}, {1, 3, 2}, {2, 3, 4}, {3, 5, 4}};
  Eigen::VectorXd x(18);
  // A flat strip along x at z = 0: neighbours share corners and touch, and are skipped.
  const double strip[6][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 2, 0}, {1, 2, 0}};
  for (int n = 0; n < 6; ++n)
    x.segment<3>(3 * n) = V(strip[n][0], strip[n][1], strip[n][2]);
  EXPECT_TRUE(findSurfaceIntersections(triangles, x).empty());
  // Lift node 3 and fold node 5 under the strip: the edge between them passes through the first
  // triangle at (0.3, 0.2, 0).
  x.segment<3>(9) = V(1, 1, 1);
  x.segment<3>(15) = V(-0.4, -0.6, -1);
  const std::vector<TrianglePair> found = findSurfaceIntersections(triangles, x);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0], (TrianglePair{0, 3}));
}

TEST(FindSurfaceIntersections, AMeshAtRestHasNoneAndAFoldedOneDoes) {
  Result<TetMesh> mesh = makeBoxTetMesh(V::Zero(), V(4, 1, 0.25), 8, 2, 1);
  ASSERT_TRUE(mesh.ok());
  const std::vector<Eigen::Vector3d>& rest = mesh.value().restPositions();
  Eigen::VectorXd x(3 * static_cast<Eigen::Index>(rest.size()));
  for (size_t n = 0; n < rest.size(); ++n)
    x.segment<3>(3 * static_cast<Eigen::Index>(n)) = rest[n];
  const std::vector<Triangle>& surface = mesh.value().surfaceTriangles();
  EXPECT_TRUE(findSurfaceIntersections(surface, x).empty());
  // Fold the slab's far half (x > 2) back over the near half, 0.1 lower than flat on it: the
  // halves overlap by 0.15 in z, so their surfaces cross.
  for (size_t n = 0; n < rest.size(); ++n) {
    if (rest[n].x() <= 2) continue;
    x.segment<3>(3 * static_cast<Eigen::Index>(n)) =
        V(4 - rest[n].x(), rest[n].y(), 0.4 - rest[n].z());
  }
  EXPECT_FALSE(findSurfaceIntersections(surface, x).empty());
}

TEST(FindSurfaceIntersections, TwoBodiesCrossTouchAndPart) {
  Result<TetMesh> mesh = makeBoxTetMesh(V::Zero(), V::Ones(), 2, 2, 2);
  ASSERT_TRUE(mesh.ok());
  const std::vector<Eigen::Vector3d>& rest = mesh.value().restPositions();
  const std::vector<Triangle>& surface = mesh.value().surfaceTriangles();
  auto placed = [&](const V& offset) {
    Eigen::VectorXd x(3 * static_cast<Eigen::Index>(rest.size()));
    for (size_t n = 0; n < rest.size(); ++n)
      x.segment<3>(3 * static_cast<Eigen::Index>(n)) = rest[n] + offset;
    return x;
  };
  const Eigen::VectorXd a = placed(V::Zero());
  EXPECT_FALSE(findSurfaceIntersections(surface, a, surface, placed(V(0.5, 0.25, 0.1))).empty());
  // Face to face at x = 1: touching, which counts.
  EXPECT_FALSE(findSurfaceIntersections(surface, a, surface, placed(V(1, 0.3, 0.2))).empty());
  EXPECT_TRUE(findSurfaceIntersections(surface, a, surface, placed(V(1 + 1e-9, 0.3, 0.2))).empty());
  EXPECT_TRUE(findSurfaceIntersections(surface, a, surface, placed(V(3, 0, 0))).empty());
}

}  // namespace
}  // namespace torsion
