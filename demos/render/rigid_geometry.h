#pragma once
// What a Bullet rigid body looks like, as plain data for the renderer: its shape's parameters
// (box, sphere, capsule, plane) or its triangles (convex hull, triangle mesh) in the body's own
// frame, and its pose. Anything else falls back to its bounding box (kOther).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <vector>

class btRigidBody;

namespace torsion::render {

struct RigidDrawData {
  enum class Shape { kBox, kSphere, kCapsule, kPlane, kTriangles, kOther } shape = Shape::kOther;
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();  ///< box, or the bounds of kOther
  double radius = 0;                                       ///< sphere, capsule
  double half_height = 0;  ///< capsule: half the distance between the cap centres
  int axis = 2;            ///< capsule: the local axis (0 x, 1 y, 2 z) the caps lie on
  /// kTriangles (convex hull, triangle mesh): corners in the body frame, each triangle
  /// counter-clockwise seen from outside (a hull's outside; a mesh's right-hand-rule normal).
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< plane: n . x = offset
  double offset = 0;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  bool is_static = false;
};

/// The draw data of `body` as it is now (its world transform).
RigidDrawData rigidDrawData(const btRigidBody& body);

/// The corners of a convex hull of `points`, its faces split into triangles counter-clockwise
/// from outside (Bullet's btConvexHullComputer: exact, coplanar faces merged).
void convexHullTriangles(const std::vector<Eigen::Vector3d>& points,
                         std::vector<Eigen::Vector3d>& vertices,
                         std::vector<std::array<int, 3>>& triangles);

/// Extends `bounds` by the drawn body (nothing for a plane, which is unbounded).
void extendBounds(const RigidDrawData& rigid, Eigen::AlignedBox3d& bounds);

}  // namespace torsion::render
