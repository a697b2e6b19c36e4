#include "torsion/contact/query/feature_contacts.h"

#include <BulletCollision/CollisionShapes/btBoxShape.h>
#include <BulletCollision/CollisionShapes/btConvexHullShape.h>
#include <LinearMath/btConvexHullComputer.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>

#include "torsion/bt_conversions.h"
#include "torsion/contact/surface_candidates.h"

namespace torsion {

namespace {

// Edges closer to parallel than this (sine of their angle) have no single crossing point: the
// corners and the nodes at their ends hold them.
constexpr double kParallelSine = 1e-2;
// rad: how far outside an edge's normal cone a crossing's normal may lie. A flat surface's cone
// is a single direction; a box's bottom edge tilted by less than this from it still meets the
// edges it crosses.
constexpr double kConeTolerance = 0.2;

// Parameters (s, t) of the closest points p0 + s (p1 - p0) and q0 + t (q1 - q0) of two lines
// that are not parallel.
std::pair<double, double> closestLineParameters(const Eigen::Vector3d& p0,
                                                const Eigen::Vector3d& p1,
                                                const Eigen::Vector3d& q0,
                                                const Eigen::Vector3d& q1) {
  const Eigen::Vector3d d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.dot(d1), e = d2.dot(d2), b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
  const double det = a * e - b * b;
  const double s = (b * f - c * e) / det;
  const double t = (a * f - b * c) / det;
  return {s, t};
}

bool inside(double parameter) {
  return parameter >= 0 && parameter <= 1;
}

// Whether the unit direction m lies within `tolerance` (rad) of the arc between the unit normals
// n1 and n2 of the two faces at an edge of direction d, all seen in the plane normal to d.
bool inNormalCone(const Eigen::Vector3d& m, const Eigen::Vector3d& n1, const Eigen::Vector3d& n2,
                  const Eigen::Vector3d& d) {
  const Eigen::Vector3d axis = d.normalized();
  auto flat = [&](const Eigen::Vector3d& v) { return Eigen::Vector3d(v - axis * axis.dot(v)); };
  const Eigen::Vector3d a = flat(n1), b = flat(n2), x = flat(m);
  double arc = std::atan2(a.cross(b).dot(axis), a.dot(b));
  double at = std::atan2(a.cross(x).dot(axis), a.dot(x));
  if (arc < 0) {
    arc = -arc;
    at = -at;
  }
  return at >= -kConeTolerance && at <= arc + kConeTolerance;
}

// A hull face's outward unit normal from three of its vertices, oriented away from `centroid`.
Eigen::Vector3d hullFaceNormal(const btConvexHullComputer& hull,
                               const btConvexHullComputer::Edge& e,
                               const Eigen::Vector3d& centroid) {
  const Eigen::Vector3d v0 = toEigen(hull.vertices[e.getSourceVertex()]);
  const Eigen::Vector3d v1 = toEigen(hull.vertices[e.getTargetVertex()]);
  const Eigen::Vector3d v2 = toEigen(hull.vertices[e.getNextEdgeOfFace()->getTargetVertex()]);
  Eigen::Vector3d n = (v1 - v0).cross(v2 - v0).normalized();
  if (n.dot(v0 - centroid) < 0) n = -n;
  return n;
}

// The hull's edges, each once, with the outward normals of its two faces (hull frame).
void addHullEdges(const btConvexHullComputer& hull, PolyhedronFeatures& f) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i = 0; i < hull.vertices.size(); ++i)
    centroid += toEigen(hull.vertices[i]);
  centroid /= hull.vertices.size();
  std::set<std::array<int, 2>> seen;
  for (int i = 0; i < hull.edges.size(); ++i) {
    const btConvexHullComputer::Edge& e = hull.edges[i];
    const int from = e.getSourceVertex(), to = e.getTargetVertex();
    if (!seen.insert({std::min(from, to), std::max(from, to)}).second) continue;
    f.edges.push_back({from, to});
    f.edge_faces.push_back(
        {hullFaceNormal(hull, e, centroid), hullFaceNormal(hull, *e.getReverseEdge(), centroid)});
  }
}

}  // namespace

bool hasPolyhedronFeatures(const btCollisionShape& shape) {
  return shape.getShapeType() == BOX_SHAPE_PROXYTYPE ||
         shape.getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE;
}

std::optional<PolyhedronFeatures> polyhedronFeatures(const btCollisionShape& shape,
                                                     const btTransform& transform) {
  PolyhedronFeatures f;
  f.centre = toEigen(transform.getOrigin());
  if (shape.getShapeType() == BOX_SHAPE_PROXYTYPE) {
    const auto& box = static_cast<const btBoxShape&>(shape);
    for (int i = 0; i < box.getNumVertices(); ++i) {
      btVector3 v;
      box.getVertex(i, v);
      f.vertices.push_back(toEigen(transform * v));
    }
    // btBoxShape::getVertex numbers corner i by its bits (x, y, z negative when set): an edge
    // joins two corners that differ in one bit, between the faces of the other two axes.
    const btMatrix3x3& basis = transform.getBasis();
    for (int i = 0; i < 8; ++i) {
      for (int axis = 0; axis < 3; ++axis) {
        const int bit = 1 << axis;
        if ((i & bit) != 0) continue;
        f.edges.push_back({i, i | bit});
        std::array<Eigen::Vector3d, 2> faces;
        for (int k = 1; k <= 2; ++k) {
          const int other = (axis + k) % 3;
          const double sign = (i & (1 << other)) != 0 ? -1.0 : 1.0;
          faces[static_cast<size_t>(k - 1)] = sign * toEigen(basis.getColumn(other));
        }
        f.edge_faces.push_back(faces);
      }
    }
    return f;
  }
  if (shape.getShapeType() == CONVEX_HULL_SHAPE_PROXYTYPE) {
    const auto& hull_shape = static_cast<const btConvexHullShape&>(shape);
    // Fewer than four points have no volume (and an empty hull has no point array at all).
    if (hull_shape.getNumPoints() < 4) return std::nullopt;
    const btVector3* points = hull_shape.getUnscaledPoints();
    std::vector<btVector3> scaled(static_cast<size_t>(hull_shape.getNumPoints()));
    for (size_t i = 0; i < scaled.size(); ++i)
      scaled[i] = points[i] * hull_shape.getLocalScaling();
    btConvexHullComputer hull;
    hull.compute(scaled.front().m_floats, static_cast<int>(sizeof(btVector3)),
                 static_cast<int>(scaled.size()), 0, 0);
    if (hull.vertices.size() < 4) return std::nullopt;
    for (int i = 0; i < hull.vertices.size(); ++i)
      f.vertices.push_back(toEigen(transform * hull.vertices[i]));
    addHullEdges(hull, f);
    const Eigen::Matrix3d rotation = toEigen(transform.getBasis());
    for (std::array<Eigen::Vector3d, 2>& faces : f.edge_faces)
      faces = {rotation * faces[0], rotation * faces[1]};
    f.margin = toDouble(hull_shape.getMargin());
    return f;
  }
  return std::nullopt;
}

FaceContact FeatureContactCollector::contactAt(const Eigen::Vector3d& shape_point,
                                               const Eigen::Vector3d& normal, double gap) const {
  FaceContact fc;
  fc.partner = partner_;
  fc.normal = normal;
  fc.gap = gap;
  fc.lever = shape_point - partner_data_.com;
  fc.friction = friction_;
  return fc;
}

void FeatureContactCollector::addTriangle(const Triangle& tri, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d cross = (b - a).cross(c - a);
  if (cross.squaredNorm() == 0) return;
  const Eigen::Vector3d outward = cross.normalized();
  const std::array<Eigen::Vector3d, 3> x{a, b, c};
  for (size_t v = 0; v < features_.vertices.size(); ++v)
    addCorner(static_cast<int>(v), tri, x, outward);
  for (size_t k = 0; k < 3; ++k) {
    const int first = tri[k], second = tri[(k + 1) % 3];
    SurfaceEdge& edge = surface_edges_[{std::min(first, second), std::max(first, second)}];
    edge.from = first < second ? x[k] : x[(k + 1) % 3];
    edge.to = first < second ? x[(k + 1) % 3] : x[k];
    edge.outward.push_back(outward);
  }
}

void FeatureContactCollector::addCorner(int vertex, const Triangle& tri,
                                        const std::array<Eigen::Vector3d, 3>& x,
                                        const Eigen::Vector3d& outward) {
  const Eigen::Vector3d& corner = features_.vertices[static_cast<size_t>(vertex)];
  const double height = (corner - x[0]).dot(outward);
  const double gap = height - features_.margin;
  if (gap > reach_ || gap < -reach_) return;
  // The shape lies on the triangle's outer side: a corner of a shape beside the body is not
  // over the triangle's plane's extension.
  if ((features_.centre - corner).dot(outward) <= 0) return;
  const Eigen::Vector3d w = projectionWeights(corner - height * outward, x[0], x[1], x[2]);
  if (w.minCoeff() < 0) return;
  const auto found = corners_.find(vertex);
  if (found != corners_.end() && found->second.gap >= gap) return;
  FaceContact fc = contactAt(corner - features_.margin * outward, -outward, gap);
  fc.nodes = {tri[0], tri[1], tri[2]};
  fc.weights = w;
  fc.key = fc.nodes;
  std::sort(fc.key.begin(), fc.key.end());
  corners_[vertex] = fc;
}

void FeatureContactCollector::addEdgeCrossing(int edge, const std::pair<int, int>& nodes,
                                              const SurfaceEdge& surface,
                                              std::vector<FaceContact>& out) const {
  const std::array<int, 2>& ends = features_.edges[static_cast<size_t>(edge)];
  const Eigen::Vector3d& p0 = features_.vertices[static_cast<size_t>(ends[0])];
  const Eigen::Vector3d& p1 = features_.vertices[static_cast<size_t>(ends[1])];
  const Eigen::Vector3d along = surface.to - surface.from;
  Eigen::Vector3d normal = (p1 - p0).cross(along);
  if (normal.norm() <= kParallelSine * (p1 - p0).norm() * along.norm()) return;
  const auto [s, t] = closestLineParameters(p0, p1, surface.from, surface.to);
  if (!inside(s) || !inside(t)) return;
  const Eigen::Vector3d on_shape = p0 + s * (p1 - p0), on_surface = surface.from + t * along;
  normal.normalize();
  // From the shape to the surface: away from the shape's centre.
  if ((on_shape - features_.centre).dot(normal) < 0) normal = -normal;
  const std::array<Eigen::Vector3d, 2>& faces = features_.edge_faces[static_cast<size_t>(edge)];
  if (!inNormalCone(normal, faces[0], faces[1], p1 - p0)) return;
  const Eigen::Vector3d& n1 = surface.outward.front();
  const Eigen::Vector3d& n2 = surface.outward.back();
  if (!inNormalCone(-normal, n1, n2, along)) return;
  const double gap = (on_surface - on_shape).dot(normal) - features_.margin;
  if (gap > reach_ || gap < -reach_) return;
  FaceContact fc = contactAt(on_shape + features_.margin * normal, normal, gap);
  fc.nodes = {nodes.first, nodes.second, nodes.second};
  fc.weights = Eigen::Vector3d(1 - t, t, 0);
  fc.key = {nodes.first, nodes.second, -1};
  out.push_back(fc);
}

void FeatureContactCollector::appendTo(std::vector<FaceContact>& out) const {
  for (const auto& [vertex, fc] : corners_)
    out.push_back(fc);
  for (size_t e = 0; e < features_.edges.size(); ++e)
    for (const auto& [nodes, surface] : surface_edges_)
      addEdgeCrossing(static_cast<int>(e), nodes, surface, out);
}

}  // namespace torsion
