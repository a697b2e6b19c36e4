#include "rigid_geometry.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <LinearMath/btConvexHullComputer.h>

#include "torsion/bt_conversions.h"

namespace torsion::render {

namespace {

// Collects every triangle of a concave shape, three corners each, in Bullet's order.
class TriangleCollector : public btTriangleCallback {
 public:
  explicit TriangleCollector(RigidDrawData& d) : d_(d) {}
  void processTriangle(btVector3* corners, int /*part*/, int /*index*/) override {
    const int first = static_cast<int>(d_.vertices.size());
    for (int k = 0; k < 3; ++k)
      d_.vertices.push_back(toEigen(corners[k]));
    d_.triangles.push_back({first, first + 1, first + 2});
  }

 private:
  RigidDrawData& d_;
};

}  // namespace

void convexHullTriangles(const std::vector<Eigen::Vector3d>& points,
                         std::vector<Eigen::Vector3d>& vertices,
                         std::vector<std::array<int, 3>>& triangles) {
  vertices.clear();
  triangles.clear();
  if (points.empty()) return;
  btConvexHullComputer hull;
  hull.compute(points.front().data(), static_cast<int>(sizeof(Eigen::Vector3d)),
               static_cast<int>(points.size()), 0, 0);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (int i = 0; i < hull.vertices.size(); ++i) {
    vertices.push_back(toEigen(hull.vertices[i]));
    centre += vertices.back();
  }
  if (vertices.empty()) return;
  centre /= static_cast<double>(vertices.size());
  // Each face is a planar polygon, its edges counter-clockwise (btConvexHullComputer's
  // convention); split it into a fan. The orientation is checked against the hull's centre
  // anyway, so an inward-facing triangle cannot reach the renderer (it would show dark).
  for (int f = 0; f < hull.faces.size(); ++f) {
    const btConvexHullComputer::Edge* start = &hull.edges[hull.faces[f]];
    const int apex = start->getSourceVertex();
    for (const btConvexHullComputer::Edge* e = start->getNextEdgeOfFace(); e != start;
         e = e->getNextEdgeOfFace()) {
      const int b = e->getSourceVertex(), c = e->getTargetVertex();
      if (c == apex) break;
      std::array<int, 3> tri = {apex, b, c};
      const Eigen::Vector3d& p = vertices[static_cast<size_t>(apex)];
      const Eigen::Vector3d n =
          (vertices[static_cast<size_t>(b)] - p).cross(vertices[static_cast<size_t>(c)] - p);
      if (n.dot(p - centre) < 0) std::swap(tri[1], tri[2]);
      triangles.push_back(tri);
    }
  }
}

RigidDrawData rigidDrawData(const btRigidBody& body) {
  RigidDrawData d;
  const btTransform& t = body.getWorldTransform();
  d.pose.linear() = toEigen(t.getRotation()).toRotationMatrix();
  d.pose.translation() = toEigen(t.getOrigin());
  d.is_static = body.getInvMass() == 0;
  const btCollisionShape* shape = body.getCollisionShape();
  switch (shape->getShapeType()) {
    case BOX_SHAPE_PROXYTYPE:
      d.shape = RigidDrawData::Shape::kBox;
      d.half_extents = toEigen(static_cast<const btBoxShape*>(shape)->getHalfExtentsWithMargin());
      return d;
    case SPHERE_SHAPE_PROXYTYPE:
      d.shape = RigidDrawData::Shape::kSphere;
      d.radius = toDouble(static_cast<const btSphereShape*>(shape)->getRadius());
      return d;
    case CAPSULE_SHAPE_PROXYTYPE: {
      const auto* capsule = static_cast<const btCapsuleShape*>(shape);
      d.shape = RigidDrawData::Shape::kCapsule;
      d.radius = toDouble(capsule->getRadius());
      d.half_height = toDouble(capsule->getHalfHeight());
      d.axis = capsule->getUpAxis();
      return d;
    }
    case CONVEX_HULL_SHAPE_PROXYTYPE: {
      // The hull of the points; Bullet's collision surface lies its margin further out (a
      // scene's default is 1 mm: not visible).
      const auto* hull = static_cast<const btConvexHullShape*>(shape);
      std::vector<Eigen::Vector3d> points;
      for (int i = 0; i < hull->getNumPoints(); ++i)
        points.push_back(toEigen(hull->getUnscaledPoints()[i]));
      d.shape = RigidDrawData::Shape::kTriangles;
      convexHullTriangles(points, d.vertices, d.triangles);
      return d;
    }
    case STATIC_PLANE_PROXYTYPE: {
      const auto* plane = static_cast<const btStaticPlaneShape*>(shape);
      d.shape = RigidDrawData::Shape::kPlane;
      d.normal = d.pose.linear() * toEigen(plane->getPlaneNormal());
      d.offset = toDouble(plane->getPlaneConstant()) + d.normal.dot(d.pose.translation());
      return d;
    }
    default:
      break;
  }
  if (shape->isConcave()) {  // a triangle mesh: every triangle, in the body frame
    TriangleCollector collect(d);
    const btVector3 huge(BT_LARGE_FLOAT, BT_LARGE_FLOAT, BT_LARGE_FLOAT);
    static_cast<const btConcaveShape*>(shape)->processAllTriangles(&collect, -huge, huge);
    d.shape = RigidDrawData::Shape::kTriangles;
    return d;
  }
  // Anything else (a compound, a cone...): its bounding box.
  btVector3 lo, hi;
  shape->getAabb(btTransform::getIdentity(), lo, hi);
  d.shape = RigidDrawData::Shape::kOther;
  d.half_extents = 0.5 * (toEigen(hi) - toEigen(lo));
  d.pose.translation() += d.pose.linear() * (0.5 * (toEigen(hi) + toEigen(lo)));
  return d;
}

void extendBounds(const RigidDrawData& r, Eigen::AlignedBox3d& bounds) {
  switch (r.shape) {
    case RigidDrawData::Shape::kPlane:
      return;
    case RigidDrawData::Shape::kSphere:
      bounds.extend(r.pose.translation() + Eigen::Vector3d::Constant(r.radius));
      bounds.extend(r.pose.translation() - Eigen::Vector3d::Constant(r.radius));
      return;
    case RigidDrawData::Shape::kCapsule:
      for (double s : {-1.0, 1.0}) {
        const Eigen::Vector3d cap = r.pose * (s * r.half_height * Eigen::Vector3d::Unit(r.axis));
        bounds.extend(cap + Eigen::Vector3d::Constant(r.radius));
        bounds.extend(cap - Eigen::Vector3d::Constant(r.radius));
      }
      return;
    case RigidDrawData::Shape::kTriangles:
      for (const Eigen::Vector3d& v : r.vertices)
        bounds.extend(r.pose * v);
      return;
    case RigidDrawData::Shape::kBox:
    case RigidDrawData::Shape::kOther:
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d corner((c & 1) ? 1 : -1, (c & 2) ? 1 : -1, (c & 4) ? 1 : -1);
        bounds.extend(r.pose * corner.cwiseProduct(r.half_extents));
      }
      return;
  }
}

}  // namespace torsion::render
