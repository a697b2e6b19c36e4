// Render tests of the rigid shapes (label "render"): tests/data/render/rigid_shapes.json holds a
// capsule lying on the ground turned about z, a convex-hull wedge and a static triangle-mesh tent
// (all posed with a rotation), beside a small FEM block. The picture at t = 0 is compared with
// tests/data/render/rigid_shapes.png by the fixture's tolerant metric, and each way of drawing a
// shape wrongly must fail that comparison: the capsule, the hull or the tent drawn as its
// bounding box (what the renderer did before it knew them), the capsule's rotation ignored, the
// hull's triangles wound inward.
//
// Regenerate the reference after an intended change of the pictures (then look at it):
//   TORSION_UPDATE_REFERENCES=1 build/tests/render/torsion_render_tests

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "render_fixture.h"

namespace torsion::render {
namespace {

using namespace test;

// No step: the shapes as posed in the file (drawing, not physics, is under test).
const Rendered& shapes() {
  static const Rendered rendered = loadAndCapture("rigid_shapes", 0);
  return rendered;
}

RigidDrawData* find(FrameData& frame, RigidDrawData::Shape shape, bool is_static) {
  for (RigidDrawData& r : frame.rigids) {
    if (r.shape == shape && r.is_static == is_static) return &r;
  }
  return nullptr;
}

// The old fallback: the shape's bounding box in its own frame, centred where that box is.
void asBoundingBox(RigidDrawData& r) {
  Eigen::AlignedBox3d box;
  if (r.shape == RigidDrawData::Shape::kCapsule) {
    Eigen::Vector3d half = Eigen::Vector3d::Constant(r.radius);
    half[r.axis] += r.half_height;
    box.extend(half);
    box.extend(-half);
  } else {
    for (const Eigen::Vector3d& v : r.vertices)
      box.extend(v);
  }
  r.shape = RigidDrawData::Shape::kOther;
  r.half_extents = 0.5 * box.sizes();
  r.pose.translation() += r.pose.linear() * box.center();
}

TEST(RigidShapes, SceneHoldsEveryShape) {
  FrameData f = shapes().frame;
  const RigidDrawData* capsule = find(f, RigidDrawData::Shape::kCapsule, false);
  ASSERT_NE(capsule, nullptr);
  EXPECT_DOUBLE_EQ(capsule->radius, 0.14);
  EXPECT_DOUBLE_EQ(capsule->half_height, 0.26);
  EXPECT_EQ(capsule->axis, 0);
  // The wedge: 6 corners, 2 triangles for each of its 3 quads and one for each end: 8.
  const RigidDrawData* hull = find(f, RigidDrawData::Shape::kTriangles, false);
  ASSERT_NE(hull, nullptr);
  EXPECT_EQ(hull->vertices.size(), 6u);
  EXPECT_EQ(hull->triangles.size(), 8u);
  // Outward: every triangle's normal points away from the hull's centre.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& v : hull->vertices)
    centre += v / 6.0;
  for (const auto& t : hull->triangles) {
    const Eigen::Vector3d& a = hull->vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d n = (hull->vertices[static_cast<size_t>(t[1])] - a)
                                  .cross(hull->vertices[static_cast<size_t>(t[2])] - a);
    EXPECT_GT(n.dot(a - centre), 0);
  }
  // The tent: its 4 triangles as written (right-hand rule: they face up and out).
  const RigidDrawData* tent = find(f, RigidDrawData::Shape::kTriangles, true);
  ASSERT_NE(tent, nullptr);
  ASSERT_EQ(tent->triangles.size(), 4u);
  for (const auto& t : tent->triangles) {
    const Eigen::Vector3d& a = tent->vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d n = (tent->vertices[static_cast<size_t>(t[1])] - a)
                                  .cross(tent->vertices[static_cast<size_t>(t[2])] - a);
    EXPECT_GT(n.z(), 0);
  }
}

TEST(RigidShapes, MatchReference) {
  expectMatchesReference("rigid_shapes", shapes());
}

TEST(RigidShapes, CapsuleAsBoxIsCaught) {
  FrameData f = shapes().frame;
  asBoundingBox(*find(f, RigidDrawData::Shape::kCapsule, false));
  expectCaught("rigid_shapes", shapes(), f, "capsule drawn as its bounding box");
}

TEST(RigidShapes, CapsuleRotationIgnoredIsCaught) {
  FrameData f = shapes().frame;
  find(f, RigidDrawData::Shape::kCapsule, false)->pose.linear().setIdentity();
  expectCaught("rigid_shapes", shapes(), f, "capsule without its rotation");
}

TEST(RigidShapes, HullAsBoxIsCaught) {
  FrameData f = shapes().frame;
  asBoundingBox(*find(f, RigidDrawData::Shape::kTriangles, false));
  expectCaught("rigid_shapes", shapes(), f, "convex hull drawn as its bounding box");
}

TEST(RigidShapes, HullWoundInwardIsCaught) {
  FrameData f = shapes().frame;
  for (auto& t : find(f, RigidDrawData::Shape::kTriangles, false)->triangles)
    std::swap(t[1], t[2]);
  expectCaught("rigid_shapes", shapes(), f, "convex hull wound inward");
}

TEST(RigidShapes, TriangleMeshAsBoxIsCaught) {
  FrameData f = shapes().frame;
  asBoundingBox(*find(f, RigidDrawData::Shape::kTriangles, true));
  expectCaught("rigid_shapes", shapes(), f, "triangle mesh drawn as its bounding box");
}

TEST(RigidShapes, ConvexHullTrianglesOfACube) {
  // Eight corners and a point inside: the inner point is dropped, each face gives 2 triangles.
  std::vector<Eigen::Vector3d> points;
  for (int c = 0; c < 8; ++c)
    points.emplace_back((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
  points.emplace_back(0.1, 0.2, 0.3);
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  convexHullTriangles(points, vertices, triangles);
  EXPECT_EQ(vertices.size(), 8u);
  ASSERT_EQ(triangles.size(), 12u);
  double area = 0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d& a = vertices[static_cast<size_t>(t[0])];
    const Eigen::Vector3d n =
        (vertices[static_cast<size_t>(t[1])] - a).cross(vertices[static_cast<size_t>(t[2])] - a);
    EXPECT_GT(n.dot(a), 0);  // outward: the centre is the origin
    area += 0.5 * n.norm();
  }
  EXPECT_NEAR(area, 24, 1e-9);  // six faces of 2 x 2
}

}  // namespace
}  // namespace torsion::render
