#pragma once
// Signed distance from a point to a Bullet collision shape: the narrow phase of FEM-rigid contact
// (docs/contact-pipeline.md). Positive outside, negative inside; the normal is the unit direction,
// in world coordinates, in which the point leaves the shape fastest (from the shape's surface
// towards the point).
//
//   sphere, box, capsule (X/Y/Z), static plane   closed form, exact
//   any other convex shape (convex hull, cylinder, cone, ...)
//                                                Bullet's GJK/EPA
//                                                (btGjkEpaSolver2::SignedDistance), measured to the
//                                                shape's margin-inflated surface, as Bullet's own
//                                                rigid contacts are
//   triangle meshes (btConcaveShape)             the closest triangle within `search_radius`,
//                                                signed by its face normal (one-sided)

#include <BulletCollision/CollisionShapes/btCollisionShape.h>
#include <LinearMath/btTransform.h>

#include <Eigen/Core>
#include <optional>

namespace torsion {

struct SurfacePoint {
  double distance = 0;                                ///< m, signed: < 0 inside the shape
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, world, out of the shape
};

/// `preferred` (world, unit or zero) breaks ties between equally near faces of a box for a point
/// inside it, e.g. a node exactly below a box's bottom edge: the face whose normal is closest to
/// `preferred` wins (callers pass minus the soft body's surface normal at the node).
/// `search_radius` (m) bounds the query for triangle meshes (no triangle within it: nullopt) and
/// is ignored by the other shapes. nullopt as well for shapes we cannot query (compounds, soft
/// bodies) and for degenerate cases (the point at the exact centre of a sphere).
std::optional<SurfacePoint> signedDistance(
    const btCollisionShape& shape, const btTransform& transform, const Eigen::Vector3d& x,
    double search_radius, const Eigen::Vector3d& preferred = Eigen::Vector3d::Zero());

/// Signed distance from `x` to the supporting plane of a convex shape whose outward normal is the
/// unit vector `direction` (world): direction . x - h(direction), h the shape's support function
/// (margin included, the surface the other queries measure). Every supporting plane bounds the
/// shape, so this never exceeds signedDistance(x): keeping x outside it keeps x outside the
/// shape. The normal returned is `direction`. nullopt for shapes that are not convex (planes,
/// triangle meshes, compounds) or a zero direction.
std::optional<SurfacePoint> supportPlaneDistance(const btCollisionShape& shape,
                                                 const btTransform& transform,
                                                 const Eigen::Vector3d& x,
                                                 const Eigen::Vector3d& direction);

}  // namespace torsion
