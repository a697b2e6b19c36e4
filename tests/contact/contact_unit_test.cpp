// Contact narrow phase and bookkeeping: signed distances against closed forms (and libccd when
// available), the ball mesh, held nodes never moved by a contact.

#include <gtest/gtest.h>

#include "contact_fixtures.h"
#include "torsion/contact/shape_distance.h"

namespace torsion::test {
namespace {

TEST(ShapeDistance, Sphere) {
  btSphereShape s(0.5);
  auto d = signedDistance(s, at({1, 0, 0}), {1, 0, 2}, 0);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(d->distance, 1.5, 1e-12);
  EXPECT_NEAR(d->normal.z(), 1.0, 1e-12);
}

TEST(ShapeDistance, BoxOutsideInsideAndEdgeTie) {
  btBoxShape box(btVector3(0.5, 0.25, 0.1));
  auto out = signedDistance(box, at({0, 0, 0}), {0.8, 0.65, 0}, 0);
  ASSERT_TRUE(out.has_value());
  EXPECT_NEAR(out->distance, 0.5, 1e-12);  // (0.3, 0.4) from the edge
  EXPECT_NEAR(out->normal.x(), 0.6, 1e-12);
  auto in = signedDistance(box, at({0, 0, 0}), {0.45, 0, 0.0}, 0);
  ASSERT_TRUE(in.has_value());
  EXPECT_NEAR(in->distance, -0.05, 1e-12);
  EXPECT_NEAR(in->normal.x(), 1.0, 1e-12);
  // On the bottom edge: equally near the side and the bottom; the preferred direction decides.
  auto tie = signedDistance(box, at({0, 0, 0}), {0.5, 0, -0.1}, 0, {0, 0, -1});
  ASSERT_TRUE(tie.has_value());
  EXPECT_NEAR(tie->normal.z(), -1.0, 1e-12);
}

TEST(ShapeDistance, StaticPlaneAndConvexHullAgreeWithClosedForms) {
  btStaticPlaneShape plane(btVector3(0, 0, 1), 0.5);
  auto d = signedDistance(plane, at({0, 0, 0}), {3, -2, 0.2}, 0);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(d->distance, -0.3, 1e-12);
  // A hull of a cube's corners, margin 0: GJK/EPA against the box's closed form.
  btConvexHullShape hull;
  for (int c = 0; c < 8; ++c)
    hull.addPoint(btVector3(c & 1 ? 0.5 : -0.5, c & 2 ? 0.5 : -0.5, c & 4 ? 0.5 : -0.5));
  hull.setMargin(0);
  btBoxShape box(btVector3(0.5, 0.5, 0.5));
  for (const Eigen::Vector3d& x : {Eigen::Vector3d(1.2, 0.1, 0.2), Eigen::Vector3d(0.9, 0.8, -0.7),
                                   Eigen::Vector3d(0.3, 0.1, -0.05)}) {
    auto a = signedDistance(hull, at({0.1, 0, 0}), x, 0);
    auto b = signedDistance(box, at({0.1, 0, 0}), x, 0);
    ASSERT_TRUE(a.has_value() && b.has_value());
    EXPECT_NEAR(a->distance, b->distance, 1e-6) << x.transpose();
    EXPECT_GT(a->normal.dot(b->normal), 1 - 1e-6) << x.transpose();
  }
}

TEST(BallMesh, PositiveTetsOnTheSphere) {
  Result<TetMesh> ball = makeBallTetMesh({1, 2, 3}, 0.5, 4);
  ASSERT_TRUE(ball.ok()) << ball.error().message;
  double farthest = 0;
  for (const Eigen::Vector3d& p : ball.value().restPositions())
    farthest = std::max(farthest, (p - Eigen::Vector3d(1, 2, 3)).norm());
  EXPECT_NEAR(farthest, 0.5, 1e-12);
  EXPECT_FALSE(makeBallTetMesh({0, 0, 0}, 0.5, 1).ok());
}

}  // namespace
}  // namespace torsion::test
