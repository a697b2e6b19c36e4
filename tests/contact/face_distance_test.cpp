// Face narrow phase (face_distance.h): closed cases, and on random convex shapes the facts that
// make it right: the shape point is on the shape's surface, the normal joins it to the face point,
// and no point of the triangle is nearer the shape (a dense sample).

#include "torsion/contact/face_distance.h"

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btTriangleMesh.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "contact_fixtures.h"
#include "torsion/contact/shape_distance.h"

namespace torsion::test {
namespace {

// The triangle (0,0,0), (1,0,0), (0,1,0): outward normal +z, the rigid shapes above it.
const Eigen::Vector3d kA(0, 0, 0), kB(1, 0, 0), kC(0, 1, 0);

TEST(FaceDistance, SphereOverTheFaceAndInto) {
  btSphereShape sphere(0.1);
  auto f = shapeToTriangle(sphere, at({0.25, 0.25, 0.3}), kA, kB, kC, 1.0);
  ASSERT_TRUE(f.has_value());
  // Float Bullet stores the radius and the centre rounded to float (0.1 -> 0.10000000149).
  const double tol = atBulletPrecision(1e-12);
  EXPECT_NEAR(f->distance, 0.2, tol);
  EXPECT_NEAR(f->normal.z(), -1.0, tol);
  EXPECT_NEAR((f->barycentric - Eigen::Vector3d(0.5, 0.25, 0.25)).norm(), 0, tol);
  EXPECT_NEAR((f->shape_point - Eigen::Vector3d(0.25, 0.25, 0.2)).norm(), 0, tol);
  auto into = shapeToTriangle(sphere, at({0.25, 0.25, 0.05}), kA, kB, kC, 1.0);
  ASSERT_TRUE(into.has_value());
  EXPECT_NEAR(into->distance, -0.05, tol);
  // Its centre behind the face: gone through, not a contact of this face.
  EXPECT_FALSE(shapeToTriangle(sphere, at({0.25, 0.25, -0.02}), kA, kB, kC, 1.0).has_value());
}

// A cube standing on a corner (its diagonal along z), the corner over (0.3, 0.3).
btTransform cornerDown(double corner_height, double half) {
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(
      Eigen::Vector3d(-1, -1, -1).normalized(), Eigen::Vector3d(0, 0, -1));
  btTransform t;
  t.setRotation(btQuaternion(q.x(), q.y(), q.z(), q.w()));
  t.setOrigin(btVector3(0.3, 0.3, corner_height + half * std::sqrt(3.0)));
  return t;
}

TEST(FaceDistance, BoxCornerAboveAndIntoTheFace) {
  btBoxShape box(btVector3(0.1, 0.1, 0.1));  // margin inside the half extents, as Bullet's
  for (double height : {0.01, 1e-4, -1e-4, -0.003}) {
    auto f = shapeToTriangle(box, cornerDown(height, 0.1), kA, kB, kC, 0.05);
    ASSERT_TRUE(f.has_value()) << height;
    // Exact for a point under the face, also when the corner is through it (the offset search),
    // to the resolution of Bullet's pose and GJK (float Bullet: 3e-8 m measured here).
    EXPECT_NEAR(f->distance, height, atBulletPrecision(1e-9)) << height;
    EXPECT_NEAR(f->normal.z(), -1.0, atBulletPrecision(1e-9)) << height;
    EXPECT_NEAR((f->barycentric - Eigen::Vector3d(0.4, 0.3, 0.3)).norm(), 0, 1e-7) << height;
  }
}

TEST(FaceDistance, PlanesAreLeftToNodes) {
  btStaticPlaneShape plane(btVector3(0, 0, 1), 0);
  EXPECT_FALSE(shapeToTriangle(plane, at({0, 0, 0}), kA, kB, kC, 1.0).has_value());
}

TEST(FaceDistance, TriangleMeshApexUnderASoftBottomFace) {
  // The soft body is above: its bottom face (0,0,0), (0,1,0), (1,0,0) faces down. A static mesh
  // pyramid below points its apex up at (0.3, 0.3, -0.01).
  btTriangleMesh mesh;
  const btVector3 apex(0.3, 0.3, -0.01);
  const btVector3 base[4] = {
      {-0.2, -0.2, -0.3}, {0.8, -0.2, -0.3}, {0.8, 0.8, -0.3}, {-0.2, 0.8, -0.3}};
  for (int k = 0; k < 4; ++k)
    mesh.addTriangle(base[k], base[(k + 1) % 4], apex);  // counter-clockwise from outside
  btBvhTriangleMeshShape shape(&mesh, true);
  auto f = shapeToTriangle(shape, at({0, 0, 0}), kA, kC, kB, 0.05);
  ASSERT_TRUE(f.has_value());
  EXPECT_NEAR(f->distance, 0.01, 1e-9);
  EXPECT_NEAR(f->normal.z(), 1.0, 1e-9);
  EXPECT_NEAR((f->barycentric - Eigen::Vector3d(0.4, 0.3, 0.3)).norm(), 0, 1e-7);
}

TEST(FaceDistance, RandomConvexShapesAgreeWithNodeDistancesAndDenseSampling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  btBoxShape box(btVector3(0.15, 0.1, 0.05));
  btCapsuleShapeZ capsule(0.05, 0.2);
  btSphereShape sphere(0.08);
  btConvexHullShape hull;
  for (int k = 0; k < 12; ++k)
    hull.addPoint(btVector3(0.15 * u(rng), 0.15 * u(rng), 0.15 * u(rng)));
  hull.setMargin(0.01);  // the node distance measures to the margin-inflated surface too
  const btCollisionShape* shapes[] = {&box, &capsule, &sphere, &hull};
  int checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const btCollisionShape& shape = *shapes[trial % 4];
    Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
    q.normalize();
    btTransform t;
    t.setRotation(btQuaternion(q.x(), q.y(), q.z(), q.w()));
    t.setOrigin(btVector3(0.5 * u(rng) + 0.3, 0.5 * u(rng) + 0.3, 0.25 + 0.1 * u(rng)));
    const auto f = shapeToTriangle(shape, t, kA, kB, kC, 1.0);
    if (!f || f->distance <= 1e-6) continue;  // separated cases: the sample bound is one-sided
    ++checked;
    const Eigen::Vector3d on_face =
        f->barycentric[0] * kA + f->barycentric[1] * kB + f->barycentric[2] * kC;
    EXPECT_NEAR(f->barycentric.sum(), 1.0, 1e-12);
    EXPECT_GE(f->barycentric.minCoeff(), -1e-12);
    // The shape point is on the surface, the normal joins it to the face point ...
    const auto surface = signedDistance(shape, t, f->shape_point, 1.0);
    ASSERT_TRUE(surface.has_value());
    EXPECT_NEAR(surface->distance, 0.0, 1e-6) << trial;
    EXPECT_NEAR((f->shape_point + f->distance * f->normal - on_face).norm(), 0.0, 1e-6) << trial;
    // ... and no point of a 100 x 100 sample of the triangle is nearer (within round-off).
    double nearest = 1e300;
    for (int i = 0; i <= 100; ++i) {
      for (int j = 0; i + j <= 100; ++j) {
        const Eigen::Vector3d p = kA + (kB - kA) * (i / 100.0) + (kC - kA) * (j / 100.0);
        nearest = std::min(nearest, signedDistance(shape, t, p, 1.0)->distance);
      }
    }
    EXPECT_LE(f->distance, nearest + 1e-7) << trial;
    // The sample is 1/100 of the triangle apart: the nearest sample is within that (Lipschitz 1).
    EXPECT_LE(nearest - f->distance, 0.01 * std::sqrt(2.0)) << trial;
  }
  EXPECT_GT(checked, 100);
}

}  // namespace
}  // namespace torsion::test
