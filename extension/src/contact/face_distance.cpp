#include "torsion/contact/face_distance.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btConcaveShape.h>
#include <BulletCollision/CollisionShapes/btSphereShape.h>
#include <BulletCollision/CollisionShapes/btTriangleCallback.h>
#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpa2.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/contact/shape_distance.h"

namespace torsion {

Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                       Eigen::Vector3d* barycentric) {
  Eigen::Vector3d w;
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0 && d2 <= 0) {
    w = {1, 0, 0};
  } else if (d3 >= 0 && d4 <= d3) {
    w = {0, 1, 0};
  } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    w = {1 - t, t, 0};
  } else if (d6 >= 0 && d5 <= d6) {
    w = {0, 0, 1};
  } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    w = {1 - t, 0, t};
  } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    w = {0, 1 - t, t};
  } else {
    const double denom = 1 / (va + vb + vc);
    w = {1 - (vb + vc) * denom, vb * denom, vc * denom};
  }
  if (barycentric != nullptr) *barycentric = w;
  return w[0] * a + w[1] * b + w[2] * c;
}

namespace {

using Corners = std::array<Eigen::Vector3d, 3>;

Eigen::Vector3d unitNormal(const Corners& t) {
  return (t[1] - t[0]).cross(t[2] - t[0]).normalized();
}

std::optional<FacePoint> sphereToTriangle(const Eigen::Vector3d& centre, double radius,
                                          const Corners& t) {
  FacePoint f;
  const Eigen::Vector3d q = closestPointOnTriangle(centre, t[0], t[1], t[2], &f.barycentric);
  const double d = (q - centre).norm();
  // A centre on or behind the face's plane has gone through it: beyond what one step resolves.
  if (d == 0 || unitNormal(t).dot(centre - q) <= 0) return std::nullopt;
  f.normal = (q - centre) / d;
  f.distance = d - radius;
  f.shape_point = centre + radius * f.normal;
  return f;
}

// Bullet's GJK between a convex shape (its margin excluded) and the triangle moved inward by
// `offset`; the result is for the triangle where it is.
std::optional<FacePoint> gjkToTriangle(const btConvexShape& convex, double margin,
                                       const btTransform& transform, const Corners& t,
                                       double search_radius) {
  const Eigen::Vector3d n = unitNormal(t);
  btTransform identity;
  identity.setIdentity();
  // Overlaps: try deeper offsets, each 4x the last, up to the search radius.
  const double first = std::max(1e-6, 1e-3 * search_radius);
  for (double offset = 0; offset <= search_radius; offset = offset == 0 ? first : 4 * offset) {
    const Eigen::Vector3d shift = -offset * n;
    btTriangleShape triangle(toBt(t[0] + shift), toBt(t[1] + shift), toBt(t[2] + shift));
    triangle.setMargin(0);
    btGjkEpaSolver2::sResults r;
    if (!btGjkEpaSolver2::Distance(&convex, transform, &triangle, identity, toBt(-n), r)) continue;
    const Eigen::Vector3d on_shape = toEigen(r.witnesses[0]);
    const Eigen::Vector3d on_face = toEigen(r.witnesses[1]) - shift;
    const double gap = (toEigen(r.witnesses[1]) - on_shape).norm();
    // Touching at the offset: GJK's direction is undefined; go deeper.
    if (gap <= 1e-9 * std::max(1.0, search_radius)) continue;
    FacePoint f;
    f.normal = (toEigen(r.witnesses[1]) - on_shape) / gap;
    // The shape must be in front of the face (a shape behind it is the business of the body's
    // other side, and a one-sided contact would pull it through).
    if (f.normal.dot(n) >= 0) return std::nullopt;
    f.distance = gap - margin - offset * (-n).dot(f.normal);
    f.shape_point = on_shape + margin * f.normal;
    closestPointOnTriangle(on_face, t[0], t[1], t[2], &f.barycentric);
    return f;
  }
  return std::nullopt;
}

// GJK stops within about 1e-4 of the distance and its face point can be off by as much.
// Alternating projections (the shape's exact closest point to the face point, then the face's to
// that) converge to the closest pair of two convex sets and only ever shorten the distance: a few
// of them polish GJK's answer, with the exact point distance (closed form for boxes). Only while
// both are clear of the shape (inside, the nearest exit of a point may run along the face).
std::optional<FacePoint> polish(const btCollisionShape& shape, const btTransform& transform,
                                const Corners& t, std::optional<FacePoint> f) {
  if (!f || f->distance <= 0) return f;
  Eigen::Vector3d weights = f->barycentric;
  Eigen::Vector3d on_face = weights[0] * t[0] + weights[1] * t[1] + weights[2] * t[2];
  std::optional<SurfacePoint> best;
  Eigen::Vector3d best_weights = weights;
  for (int k = 0; k < 32; ++k) {
    const std::optional<SurfacePoint> exact = signedDistance(shape, transform, on_face, 0);
    if (!exact || exact->distance <= 0 || exact->normal.dot(unitNormal(t)) >= 0) break;
    if (best && exact->distance >= best->distance) break;
    best = exact;
    best_weights = weights;
    const Eigen::Vector3d on_shape = on_face - exact->distance * exact->normal;
    const Eigen::Vector3d next = closestPointOnTriangle(on_shape, t[0], t[1], t[2], &weights);
    if ((next - on_face).norm() < 1e-13) break;
    on_face = next;
  }
  // GJK runs in btScalar: on float Bullet its distance carries the float rounding of the
  // coordinates and may come out below the exact one; within that it is not a better answer.
  // Double Bullet keeps the strict comparison (the regression scenes' states depend on it).
  const double gjk_rounding =
      kBulletIsDouble
          ? 0.0
          : 16 * kBulletEpsilon * (on_face.norm() + toEigen(transform.getOrigin()).norm());
  if (!best || best->distance > f->distance + gjk_rounding) return f;
  f->barycentric = best_weights;
  on_face = best_weights[0] * t[0] + best_weights[1] * t[1] + best_weights[2] * t[2];
  f->distance = best->distance;
  f->normal = best->normal;
  f->shape_point = on_face - best->distance * best->normal;
  return f;
}

// The nearest triangle of a concave shape facing the FEM triangle.
class NearestFacingTriangle : public btTriangleCallback {
 public:
  NearestFacingTriangle(const Corners& face, double search_radius)
      : face_(face), search_radius_(search_radius) {}
  void processTriangle(btVector3* v, int /*part*/, int /*index*/) override {
    btTriangleShape rigid(v[0], v[1], v[2]);
    rigid.setMargin(0);
    btTransform identity;
    identity.setIdentity();
    std::optional<FacePoint> f = gjkToTriangle(rigid, 0, identity, face_, search_radius_);
    if (!f) return;
    const Eigen::Vector3d front =
        toEigen((v[1] - v[0]).cross(v[2] - v[0])).normalized();  // out of the mesh's front
    if (front.dot(f->normal) <= 0) return;
    if (!best_ || f->distance < best_->distance) best_ = f;
  }
  const std::optional<FacePoint>& best() const { return best_; }

 private:
  Corners face_;
  double search_radius_;
  std::optional<FacePoint> best_;
};

}  // namespace

std::optional<FacePoint> shapeToTriangle(const btCollisionShape& shape,
                                         const btTransform& transform, const Eigen::Vector3d& a,
                                         const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                         double search_radius) {
  const Corners t{a, b, c};
  if ((b - a).cross(c - a).squaredNorm() == 0) return std::nullopt;
  switch (shape.getShapeType()) {
    case SPHERE_SHAPE_PROXYTYPE:
      return sphereToTriangle(toEigen(transform.getOrigin()),
                              static_cast<const btSphereShape&>(shape).getRadius(), t);
    case BOX_SHAPE_PROXYTYPE: {
      // Sharp, at the half extents Bullet collides with (shape_distance.h): the margin-rounded
      // corners of Bullet's GJK box would let a corner 4 cm into a face undetected.
      btBoxShape sharp(static_cast<const btBoxShape&>(shape).getHalfExtentsWithMargin());
      sharp.setMargin(0);
      return polish(shape, transform, t, gjkToTriangle(sharp, 0, transform, t, search_radius));
    }
    case STATIC_PLANE_PROXYTYPE:
      return std::nullopt;
    default:
      break;
  }
  if (shape.isConvex()) {
    const auto& convex = static_cast<const btConvexShape&>(shape);
    return polish(shape, transform, t,
                  gjkToTriangle(convex, convex.getMargin(), transform, t, search_radius));
  }
  if (shape.isConcave()) {
    // The mesh's triangles are in its local frame: bring the FEM triangle there and back.
    const btTransform inverse = transform.inverse();
    Corners local;
    btVector3 lo(SIMD_INFINITY, SIMD_INFINITY, SIMD_INFINITY), hi = -lo;
    for (size_t k = 0; k < 3; ++k) {
      local[k] = worldPoint(inverse, t[k]);
      const btVector3 p = toBt(local[k]);
      lo.setMin(p);
      hi.setMax(p);
    }
    const btVector3 pad = toBt(Eigen::Vector3d::Constant(search_radius));
    NearestFacingTriangle nearest(local, search_radius);
    static_cast<const btConcaveShape&>(shape).processAllTriangles(&nearest, lo - pad, hi + pad);
    std::optional<FacePoint> f = nearest.best();
    if (f) {
      f->normal = worldDirection(transform.getBasis(), f->normal);
      f->shape_point = worldPoint(transform, f->shape_point);
    }
    return f;
  }
  return std::nullopt;
}

}  // namespace torsion
