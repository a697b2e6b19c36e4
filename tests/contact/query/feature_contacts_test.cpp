// Corner and edge contacts of polyhedral shapes with an FEM surface (query/feature_contacts.h):
// where they are, their normals and gaps, against the geometry worked by hand.

#include "torsion/contact/query/feature_contacts.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "torsion/bt_conversions.h"

namespace torsion {
namespace {

constexpr double kHalf = 0.1;    // m, the box's half side
constexpr double kReach = 0.01;  // m
// m: the geometry is exact up to the rounding of Bullet's poses and vertices (btScalar): 1e-12 in
// double, a few float ulps of the 0.2 m scale (1.2e-7 relative) in float.
constexpr double kTol = sizeof(btScalar) == sizeof(double) ? 1e-12 : 1e-7;

/// A flat square grid in z = 0 (outward normal +z), `cells` x `cells` of side `cell`, centred at
/// the origin, each square split along a diagonal.
struct Surface {
  std::vector<Eigen::Vector3d> x;
  std::vector<Triangle> triangles;
};

Surface flatGrid(int cells, double cell) {
  Surface s;
  const double origin = -0.5 * cells * cell;
  for (int j = 0; j <= cells; ++j)
    for (int i = 0; i <= cells; ++i)
      s.x.emplace_back(origin + i * cell, origin + j * cell, 0.0);
  auto id = [cells](int i, int j) { return j * (cells + 1) + i; };
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

std::vector<FaceContact> collect(const btCollisionShape& shape, const btTransform& pose,
                                 const Surface& s) {
  const std::optional<PolyhedronFeatures> features = polyhedronFeatures(shape, pose);
  EXPECT_TRUE(features.has_value());
  RigidPartner partner;
  partner.com = toEigen(pose.getOrigin());
  FeatureContactCollector collector(*features, kReach, 0, partner, 0.5);
  for (const Triangle& t : s.triangles)
    collector.addTriangle(t, s.x[static_cast<size_t>(t[0])], s.x[static_cast<size_t>(t[1])],
                          s.x[static_cast<size_t>(t[2])]);
  std::vector<FaceContact> contacts;
  collector.appendTo(contacts);
  return contacts;
}

Eigen::Vector3d facePoint(const FaceContact& c, const Surface& s) {
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < 3; ++j)
    p += c.weights[static_cast<Eigen::Index>(j)] * s.x[static_cast<size_t>(c.nodes[j])];
  return p;
}

btTransform boxPose(double height, double yaw) {
  btTransform pose;
  pose.setIdentity();
  pose.setOrigin(btVector3(0.013, -0.021, btScalar(kHalf + height)));
  pose.setRotation(btQuaternion(btVector3(0, 0, 1), btScalar(yaw)));
  return pose;
}

// A box 1 mm above a flat surface, or 1 um into it, its corners inside triangles: four corner
// contacts under its bottom corners and a contact wherever a bottom edge crosses a surface edge,
// all with the surface's inward normal and the box's height as gap, each on the box's bottom
// face, each once. Nothing from its top (out of reach) nor from its vertical edges, which cross
// the surface's edges once the box sinks in: their normals would be horizontal, outside a flat
// surface's normal cone, and stop a sliding box as a wall.
TEST(FeatureContacts, BoxOnFlatSurfaceMeetsItAlongItsBottomOnly) {
  const Surface s = flatGrid(7, 0.1);
  const btBoxShape box(btVector3(kHalf, kHalf, kHalf));
  for (double height : {1e-3, -1e-6})
    for (double yaw : {0.0, 0.3, 0.785398}) {
      const btTransform pose = boxPose(height, yaw);
      const std::vector<FaceContact> contacts = collect(box, pose, s);
      int corners = 0, crossings = 0;
      for (const FaceContact& c : contacts) {
        EXPECT_NEAR(c.gap, height, kTol) << yaw;
        EXPECT_LT((c.normal - Eigen::Vector3d(0, 0, -1)).norm(), kTol) << yaw;
        EXPECT_NEAR(c.weights.sum(), 1.0, kTol);
        // The rigid point is on the box's bottom face, right above the face point.
        const Eigen::Vector3d rigid = toEigen(pose.getOrigin()) + c.lever;
        EXPECT_NEAR(rigid.z(), height, kTol);
        EXPECT_LT((rigid - facePoint(c, s) - Eigen::Vector3d(0, 0, height)).norm(), kTol);
        const Eigen::Vector3d local = toEigen(pose.getBasis()).transpose() * c.lever;
        EXPECT_NEAR(std::max(std::abs(local.x()), std::abs(local.y())), kHalf, kTol);
        (c.weights.minCoeff() == 0 ? crossings : corners) += 1;
      }
      EXPECT_EQ(corners, 4) << yaw;
      EXPECT_GT(crossings, 0) << yaw;
      std::vector<Eigen::Vector3d> levers;
      for (const FaceContact& c : contacts)
        levers.push_back(c.lever);
      for (size_t i = 0; i < levers.size(); ++i)
        for (size_t j = i + 1; j < levers.size(); ++j)
          EXPECT_GT((levers[i] - levers[j]).norm(), 1e-9) << "a feature contact found twice";
    }
}

TEST(FeatureContacts, BoxOutOfReachHasNone) {
  const Surface s = flatGrid(7, 0.1);
  const btBoxShape box(btVector3(kHalf, kHalf, kHalf));
  EXPECT_TRUE(collect(box, boxPose(2 * kReach, 0.3), s).empty());
}

// A roof ridge along y (faces sloping down at 45 deg to either side, no node near the box) under a
// box whose bottom edges cross it: the ridge holds the box at the two crossings, normal straight
// down (inside the ridge's normal cone), gap the box's height above the ridge. Its corners are
// 1 mm + 0.1 m above the sloping faces, beyond reach.
TEST(FeatureContacts, BoxEdgesRestOnARidgeBetweenNodes) {
  Surface s;
  s.x = {{0, -1, 0}, {0, 1, 0}, {-1, -1, -1}, {-1, 1, -1}, {1, -1, -1}, {1, 1, -1}};
  s.triangles = {{0, 1, 3}, {0, 3, 2}, {0, 4, 5}, {0, 5, 1}};  // counter-clockwise from above
  const btBoxShape box(btVector3(kHalf, kHalf, kHalf));
  btTransform pose;
  pose.setIdentity();
  pose.setOrigin(btVector3(0, 0, btScalar(kHalf + 2e-3)));
  const std::vector<FaceContact> contacts = collect(box, pose, s);
  ASSERT_EQ(contacts.size(), 2u);
  for (const FaceContact& c : contacts) {
    EXPECT_NEAR(c.gap, 2e-3, kTol);
    EXPECT_LT((c.normal - Eigen::Vector3d(0, 0, -1)).norm(), kTol);
    EXPECT_NEAR(std::abs(c.lever.y()), kHalf, kTol);
    EXPECT_NEAR(c.lever.x(), 0.0, kTol);
    EXPECT_EQ(c.weights.z(), 0.0);  // on the ridge's edge, between its two nodes
    EXPECT_NEAR(facePoint(c, s).y(), c.lever.y(), kTol);
  }
}

// A convex hull of the box's corners (no margin) is the same polyhedron: the same contacts.
TEST(FeatureContacts, ConvexHullOfABoxMeetsTheSurfaceAsTheBox) {
  const Surface s = flatGrid(7, 0.1);
  const btBoxShape box(btVector3(kHalf, kHalf, kHalf));
  btConvexHullShape hull;
  for (int i = 0; i < 8; ++i) {
    btVector3 v;
    box.getVertex(i, v);
    hull.addPoint(v, false);
  }
  hull.recalcLocalAabb();
  hull.setMargin(0);
  const btTransform pose = boxPose(1e-3, 0.3);
  auto sorted = [](std::vector<FaceContact> c) {
    std::sort(c.begin(), c.end(), [](const FaceContact& a, const FaceContact& b) {
      return std::make_tuple(a.lever.x(), a.lever.y(), a.lever.z()) <
             std::make_tuple(b.lever.x(), b.lever.y(), b.lever.z());
    });
    return c;
  };
  const std::vector<FaceContact> of_box = sorted(collect(box, pose, s));
  const std::vector<FaceContact> of_hull = sorted(collect(hull, pose, s));
  ASSERT_EQ(of_box.size(), of_hull.size());
  for (size_t i = 0; i < of_box.size(); ++i) {
    EXPECT_LT((of_box[i].lever - of_hull[i].lever).norm(), kTol);
    EXPECT_NEAR(of_box[i].gap, of_hull[i].gap, kTol);
    EXPECT_LT((of_box[i].normal - of_hull[i].normal).norm(), kTol);
  }
}

TEST(FeatureContacts, OnlyBoxesAndConvexHullsHaveFeatures) {
  const btBoxShape box(btVector3(1, 1, 1));
  const btConvexHullShape hull;
  const btSphereShape sphere(1);
  EXPECT_TRUE(hasPolyhedronFeatures(box));
  EXPECT_TRUE(hasPolyhedronFeatures(hull));
  EXPECT_FALSE(hasPolyhedronFeatures(sphere));
  EXPECT_FALSE(polyhedronFeatures(sphere, btTransform::getIdentity()).has_value());
  // A hull of fewer than four points has no volume: no features.
  EXPECT_FALSE(polyhedronFeatures(hull, btTransform::getIdentity()).has_value());
}

}  // namespace
}  // namespace torsion
