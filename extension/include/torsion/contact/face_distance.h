#pragma once
// Signed distance from a Bullet collision shape to one triangle of an FEM body's surface: the
// narrow phase of face contacts (docs/contact-pipeline.md). Node contacts alone let a rigid feature
// smaller than the mesh spacing (a corner, an edge, a small sphere) sink between the nodes; a face
// contact holds the triangle at the point nearest the shape.
//
//   sphere                    closed form (closest point of the triangle to the centre)
//   other convex shapes       Bullet's GJK (btGjkEpaSolver2::Distance) on the shape without its
//                             margin, the margin then subtracted: the same surface as the node
//                             distances (shape_distance.h). Boxes are taken sharp, as there.
//                             An overlapping pair is measured with the triangle moved inward
//                             along its normal until GJK separates them, the offset subtracted
//                             again: exact for a point under the face, first order at an edge.
//                             EPA is not used: its least-translation direction can run along a
//                             triangle (a zero-thickness shape), which a surface contact must not.
//   triangle meshes           the nearest of its triangles within `search_radius` whose front
//                             faces the FEM triangle (one-sided, as for nodes)
//   static planes, others     nullopt: a plane cannot pass between nodes; node contacts are exact

#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <LinearMath/btTransform.h>

#include <Eigen/Core>
#include <optional>

namespace torsion {

struct FacePoint {
  double distance = 0;  ///< m, signed: < 0 when the shape is inside the triangle's body side
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, world, from the shape to the face
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  ///< of the face point (sums to 1)
  Eigen::Vector3d shape_point = Eigen::Vector3d::Zero();  ///< world, nearest point of the shape
};

/// Closest point of the triangle (a, b, c) to p and its barycentric coordinates
/// (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                       Eigen::Vector3d* barycentric = nullptr);

/// The triangle (a, b, c) is counter-clockwise seen from outside its body (outward normal).
/// `search_radius` (m) bounds the query: a shape farther than it may return nullopt, and an
/// overlap deeper than it is not resolved (nullopt).
std::optional<FacePoint> shapeToTriangle(const btCollisionShape& shape,
                                         const btTransform& transform, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                         double search_radius);

}  // namespace torsion
