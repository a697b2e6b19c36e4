// Contact narrow phase and bookkeeping: signed distances against closed forms (and libccd when
// available), the ball mesh, held nodes never moved by a contact.

#include <gtest/gtest.h>

#include <iostream>
#include <random>

#include "contact_fixtures.h"
#include "torsion/contact/shape_distance.h"

#ifdef TORSION_HAVE_CCD
#include <ccd/ccd.h>
#endif

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
  // (The edge of the box Bullet stores: float Bullet keeps 0.1 as 0.10000000149.)
  const double bottom = -toDouble(box.getHalfExtentsWithMargin().z());
  auto tie = signedDistance(box, at({0, 0, 0}), {0.5, 0, bottom}, 0, {0, 0, -1});
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

#ifdef TORSION_HAVE_CCD
// libccd (Debian, double precision) as an independent oracle for the penetration depth of a node
// inside a convex shape: its GJK + EPA on (point, hull) against our closed form (rotated boxes)
// and Bullet's GJK/EPA (random convex hulls), on random cases with a fixed seed.
struct CcdPoints {
  std::vector<Eigen::Vector3d> points;  // world; one point for a node
};

void ccdSupport(const void* object, const ccd_vec3_t* dir, ccd_vec3_t* out) {
  const auto& pts = static_cast<const CcdPoints*>(object)->points;
  const Eigen::Vector3d d(dir->v[0], dir->v[1], dir->v[2]);
  size_t best = 0;
  for (size_t i = 1; i < pts.size(); ++i) {
    if (pts[i].dot(d) > pts[best].dot(d)) best = i;
  }
  ccdVec3Set(out, pts[best].x(), pts[best].y(), pts[best].z());
}

// libccd's penetration depth of `node` inside the hull of `corners` (both world).
double ccdDepth(const Eigen::Vector3d& node, const std::vector<Eigen::Vector3d>& corners,
                Eigen::Vector3d& direction) {
  CcdPoints a{{node}}, b{corners};
  ccd_t ccd;
  CCD_INIT(&ccd);
  ccd.support1 = ccdSupport;
  ccd.support2 = ccdSupport;
  ccd.max_iterations = 1000;
  ccd.epa_tolerance = 1e-10;
  ccd_real_t depth = 0;
  ccd_vec3_t dir, pos;
  if (ccdGJKPenetration(&a, &b, &ccd, &depth, &dir, &pos) != 0) return -1;
  direction = Eigen::Vector3d(dir.v[0], dir.v[1], dir.v[2]);
  return depth;
}

btTransform randomPose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::Quaterniond q(u(rng), u(rng), u(rng), u(rng));
  q.normalize();
  btTransform t;
  t.setRotation(btQuaternion(q.x(), q.y(), q.z(), q.w()));
  t.setOrigin(btVector3(u(rng), u(rng), u(rng)));
  return t;
}

TEST(ShapeDistanceOracle, BoxDepthMatchesLibccd) {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> size(0.05, 1.0), unit(-1, 1);
  int directions_checked = 0;
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d half(size(rng), size(rng), size(rng));
    btBoxShape box(toBt(half));
    const btTransform pose = randomPose(rng);
    std::vector<Eigen::Vector3d> corners;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d local((c & 1 ? 1 : -1) * half.x(), (c & 2 ? 1 : -1) * half.y(),
                                  (c & 4 ? 1 : -1) * half.z());
      corners.push_back(toEigen(pose * toBt(local)));
    }
    const Eigen::Vector3d local(unit(rng) * half.x(), unit(rng) * half.y(), unit(rng) * half.z());
    const Eigen::Vector3d node = toEigen(pose * toBt(local));
    auto ours = signedDistance(box, pose, node, 0);
    ASSERT_TRUE(ours.has_value());
    Eigen::Vector3d dir;
    const double depth = ccdDepth(node, corners, dir);
    ASSERT_GE(depth, 0) << "libccd finds no intersection, trial " << trial;
    // EPA converges to 1e-10 on a polytope: agreement to a micrometre on boxes of 0.1-2 m.
    EXPECT_NEAR(-ours->distance, depth, 1e-6) << "trial " << trial;
    worst = std::max(worst, std::abs(-ours->distance - depth));
    // Direction: only where the nearest face is unique (second nearest 1 mm farther).
    Eigen::Vector3d gaps = half - local.cwiseAbs();
    std::sort(gaps.data(), gaps.data() + 3);
    if (gaps[1] - gaps[0] > 1e-3) {
      EXPECT_GT(std::abs(ours->normal.dot(dir.normalized())), 1 - 1e-6) << "trial " << trial;
      ++directions_checked;
    }
  }
  EXPECT_GT(directions_checked, 150);
  std::cout << "[figures] box depth vs libccd: worst difference " << worst << " m, "
            << directions_checked << " directions checked\n";
}

TEST(ShapeDistanceOracle, ConvexHullDepthMatchesLibccd) {
  std::mt19937 rng(66);
  std::uniform_real_distribution<double> unit(-1, 1), weight(0, 1);
  double worst = 0;
  for (int trial = 0; trial < 100; ++trial) {
    // 12 random points of an ellipsoidal cloud: their hull, margin 0 (the GJK/EPA path).
    const Eigen::Vector3d axes(0.2 + weight(rng), 0.2 + weight(rng), 0.2 + weight(rng));
    std::vector<Eigen::Vector3d> local;
    btConvexHullShape hull;
    for (int k = 0; k < 12; ++k) {
      Eigen::Vector3d p(unit(rng), unit(rng), unit(rng));
      p = p.normalized().cwiseProduct(axes);
      local.push_back(p);
      hull.addPoint(toBt(p), false);
    }
    hull.recalcLocalAabb();
    hull.setMargin(0);
    const btTransform pose = randomPose(rng);
    std::vector<Eigen::Vector3d> world;
    for (const Eigen::Vector3d& p : local)
      world.push_back(toEigen(pose * toBt(p)));
    // A node inside: a random convex combination of the points, pulled towards their centroid.
    Eigen::Vector3d node = Eigen::Vector3d::Zero(), centroid = Eigen::Vector3d::Zero();
    double total = 0;
    for (const Eigen::Vector3d& p : world) {
      const double w = weight(rng);
      node += w * p;
      total += w;
      centroid += p / static_cast<double>(world.size());
    }
    node = 0.5 * (node / total + centroid);
    auto ours = signedDistance(hull, pose, node, 0);
    ASSERT_TRUE(ours.has_value());
    Eigen::Vector3d dir;
    const double depth = ccdDepth(node, world, dir);
    ASSERT_GE(depth, 0) << "trial " << trial;
    // Bullet's EPA stops at a relative accuracy of about 1e-4 of the shape (its own tolerance);
    // 1e-5 m on hulls of 0.2-1.2 m half-axes.
    EXPECT_NEAR(-ours->distance, depth, 1e-5) << "trial " << trial;
    worst = std::max(worst, std::abs(-ours->distance - depth));
  }
  std::cout << "[figures] hull depth (Bullet GJK/EPA) vs libccd: worst difference " << worst
            << " m\n";
}
#endif

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
