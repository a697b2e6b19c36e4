// Which Bullet this build links (TORSION_BULLET_PRECISION), and what the Bullet seam keeps of the
// FEM's double precision when Bullet is float (docs/bullet-integration.md, "Bullet precision").
#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <gtest/gtest.h>

#include "torsion/bt_conversions.h"
#include "torsion/contact/shape_distance.h"

namespace torsion {
namespace {

TEST(BulletPrecision, BtScalarHasTheSizeTheBuildChose) {
  // TORSION_EXPECTED_BT_SCALAR_BYTES comes from the CMake option, independently of the define the
  // Bullet::Bullet target forwards: a target that lost BT_USE_DOUBLE_PRECISION fails here.
  EXPECT_EQ(sizeof(btScalar), static_cast<size_t>(TORSION_EXPECTED_BT_SCALAR_BYTES));
  EXPECT_EQ(kBulletIsDouble, TORSION_EXPECTED_BT_SCALAR_BYTES == 8);
}

TEST(BulletPrecision, TheLinkedBulletLibraryAgreesWithItsHeaders) {
  // btBoxShape's constructor is compiled into the library, its accessor inline here: a library of
  // the other precision (libBulletCollision vs libBulletCollision-float64, same symbols) would
  // read and write the half extents with the wrong layout.
  btBoxShape box(btVector3(0.5, 0.25, 0.125));
  const btVector3 h = box.getHalfExtentsWithMargin();
  EXPECT_EQ(h.x(), btScalar(0.5));
  EXPECT_EQ(h.y(), btScalar(0.25));
  EXPECT_EQ(h.z(), btScalar(0.125));
}

TEST(BulletPrecision, RigidFramePointsAreBulletsOwnTransformInDouble) {
  const btTransform t(btQuaternion(btVector3(1, 2, 3).normalized(), btScalar(0.7)),
                      btVector3(btScalar(0.3), btScalar(-1.2), btScalar(2.5)));
  const Eigen::Vector3d x(0.1234, -0.5, 0.75);
  const Eigen::Vector3d world = worldPoint(t, x), local = localPoint(t, x);
  const Eigen::Vector3d bullet_world = toEigen(t * toBt(x)),
                        bullet_local = toEigen(t.invXform(toBt(x)));
  if (kBulletIsDouble) {
    // The same arithmetic in the same order: bit for bit.
    EXPECT_EQ(world, bullet_world);
    EXPECT_EQ(local, bullet_local);
  } else {
    // Bullet rounds x to float first and computes in float; ours keeps x and computes in double.
    const double rounding = 8 * kBulletEpsilon * 3.0;  // coordinates below 3 m
    EXPECT_LT((world - bullet_world).norm(), rounding);
    EXPECT_LT((local - bullet_local).norm(), rounding);
  }
  // Inverse of each other to double precision for any basis Bullet holds that is orthonormal to
  // its own precision (float: 1e-7).
  EXPECT_LT((localPoint(t, world) - x).norm(), 8 * kBulletEpsilon);
}

TEST(BulletPrecision, ContactGapsKeepDoublePrecisionFarFromTheOrigin) {
  // A box 1 km from the origin, at a pose float holds exactly. A node 1 um above its top face at
  // x = 1000.1: on float Bullet, rounding the node to float first would move it by up to 30 um
  // along x and 30 nm along z. The seam measures in double: the gap is 1 um to 1e-12.
  btBoxShape box(btVector3(0.5, 0.5, 0.5));
  btTransform pose;
  pose.setIdentity();
  pose.setOrigin(btVector3(1000, 0, 0));
  const Eigen::Vector3d node(1000.1, 0.2, 0.5 + 1e-6);
  const std::optional<SurfacePoint> d = signedDistance(box, pose, node, 0);
  ASSERT_TRUE(d.has_value());
  EXPECT_NEAR(d->distance, 1e-6, 1e-12);
  EXPECT_EQ(d->normal, Eigen::Vector3d::UnitZ());
}

}  // namespace
}  // namespace torsion
