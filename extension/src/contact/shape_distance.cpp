#include "torsion/contact/shape_distance.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btCapsuleShape.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/bt_conversions.h"
#include "torsion/contact/face_distance.h"

namespace torsion {

namespace {

// Closed forms in the shape's local frame; the caller rotates the normal back.
std::optional<SurfacePoint> sphereDistance(double radius, const Eigen::Vector3d& p) {
  const double r = p.norm();
  if (r == 0) return std::nullopt;
  return SurfacePoint{r - radius, p / r};
}

SurfacePoint boxDistance(const Eigen::Vector3d& half, const Eigen::Vector3d& p,
                         const Eigen::Vector3d& preferred) {
  const Eigen::Vector3d q = p.cwiseAbs() - half;
  if ((q.array() > 0).any()) {  // outside: to the closest point of the box
    const Eigen::Vector3d outside = q.cwiseMax(0.0);
    Eigen::Vector3d n = outside.cwiseProduct(p.cwiseSign());
    const double d = n.norm();
    return SurfacePoint{d, n / d};
  }
  // Inside: leave through the nearest face; faces nearer than a round-off tolerance are ties,
  // broken by `preferred`.
  const double nearest = q.maxCoeff();
  const double tie = 1e-9 * half.maxCoeff();
  int axis = -1;
  double best = -2;
  for (int a = 0; a < 3; ++a) {
    if (q[a] < nearest - tie) continue;
    const double score = (p[a] >= 0 ? 1.0 : -1.0) * preferred[a];
    if (axis < 0 || score > best) {
      axis = a;
      best = score;
    }
  }
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  n[axis] = p[axis] >= 0 ? 1.0 : -1.0;
  return SurfacePoint{q[axis], n};
}

std::optional<SurfacePoint> capsuleDistance(double radius, double half_height, int up,
                                            const Eigen::Vector3d& p) {
  Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  closest[up] = std::clamp(p[up], -half_height, half_height);
  return sphereDistance(radius, p - closest);
}

// The closest triangle of a concave shape to a point, within a search box.
class ClosestTriangle : public btTriangleCallback {
 public:
  explicit ClosestTriangle(const Eigen::Vector3d& p) : p_(p) {}
  void processTriangle(btVector3* v, int /*part*/, int /*index*/) override {
    const Eigen::Vector3d a = toEigen(v[0]), b = toEigen(v[1]), c = toEigen(v[2]);
    Eigen::Vector3d n = (b - a).cross(c - a);
    const double area2 = n.norm();
    if (area2 == 0) return;
    n /= area2;
    const Eigen::Vector3d q = closestPointOnTriangle(p_, a, b, c);
    const double unsigned_distance = (p_ - q).norm();
    if (unsigned_distance >= best_unsigned_) return;
    best_unsigned_ = unsigned_distance;
    const double side = n.dot(p_ - a);
    // Face region: the face normal; edge or vertex region: from the closest point.
    Eigen::Vector3d normal = n;
    if (unsigned_distance > 1e-12 && std::abs(side) < unsigned_distance * (1 - 1e-9)) {
      normal = (p_ - q) / unsigned_distance;
      if (side < 0) normal = -normal;
    }
    best_ = SurfacePoint{side < 0 ? -unsigned_distance : unsigned_distance,
                         side < 0 && normal.dot(n) < 0 ? -normal : normal};
  }
  const std::optional<SurfacePoint>& best() const { return best_; }

 private:
  Eigen::Vector3d p_;
  double best_unsigned_ = std::numeric_limits<double>::infinity();
  std::optional<SurfacePoint> best_;
};

}  // namespace

std::optional<SurfacePoint> signedDistance(const btCollisionShape& shape,
                                           const btTransform& transform, const Eigen::Vector3d& x,
                                           double search_radius, const Eigen::Vector3d& preferred) {
  const Eigen::Vector3d p = localPoint(transform, x);
  std::optional<SurfacePoint> local;
  switch (shape.getShapeType()) {
    case SPHERE_SHAPE_PROXYTYPE:
      local = sphereDistance(static_cast<const btSphereShape&>(shape).getRadius(), p);
      break;
    case BOX_SHAPE_PROXYTYPE: {
      // Bullet's box collides at its half extents (the margin is inside them).
      const btVector3 h = static_cast<const btBoxShape&>(shape).getHalfExtentsWithMargin();
      local = boxDistance(toEigen(h), p, localDirection(transform.getBasis(), preferred));
      break;
    }
    case CAPSULE_SHAPE_PROXYTYPE: {
      const auto& capsule = static_cast<const btCapsuleShape&>(shape);
      local = capsuleDistance(capsule.getRadius(), capsule.getHalfHeight(), capsule.getUpAxis(), p);
      break;
    }
    case STATIC_PLANE_PROXYTYPE: {
      const auto& plane = static_cast<const btStaticPlaneShape&>(shape);
      const Eigen::Vector3d n = toEigen(plane.getPlaneNormal()).normalized();
      local = SurfacePoint{n.dot(p) - toDouble(plane.getPlaneConstant()), n};
      break;
    }
    default:
      if (shape.isConvex()) {
        btGjkEpaSolver2::sResults results;
        btTransform identity;
        identity.setIdentity();
        const btScalar d = btGjkEpaSolver2::SignedDistance(
            toBt(p), 0, static_cast<const btConvexShape*>(&shape), identity, results);
        if (d < SIMD_INFINITY) {
          // Outside, results.normal points from the shape to the point; inside, from the point
          // to the nearest surface point: out of the shape either way.
          Eigen::Vector3d n = toEigen(results.normal);
          if (n.norm() > 0) local = SurfacePoint{d, n.normalized()};
        }
      } else if (shape.isConcave()) {
        ClosestTriangle closest(p);
        const btVector3 r = toBt(Eigen::Vector3d::Constant(search_radius));
        static_cast<const btConcaveShape&>(shape).processAllTriangles(&closest, toBt(p) - r,
                                                                      toBt(p) + r);
        local = closest.best();
      }
      break;
  }
  if (!local) return std::nullopt;
  local->normal = worldDirection(transform.getBasis(), local->normal);
  return local;
}

std::optional<SurfacePoint> supportPlaneDistance(const btCollisionShape& shape,
                                                 const btTransform& transform,
                                                 const Eigen::Vector3d& x,
                                                 const Eigen::Vector3d& direction) {
  if (!shape.isConvex() || direction.squaredNorm() == 0) return std::nullopt;
  const Eigen::Vector3d u = direction.normalized();
  const btVector3 local_u = transform.getBasis().transpose() * toBt(u);
  const btVector3 support =
      transform(static_cast<const btConvexShape&>(shape).localGetSupportingVertex(local_u));
  return SurfacePoint{u.dot(x - toEigen(support)), u};
}

}  // namespace torsion
