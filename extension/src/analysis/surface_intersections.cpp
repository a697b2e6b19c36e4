#include "torsion/analysis/surface_intersections.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <numeric>
#include <utility>

#include "torsion/analysis/exact_predicates.h"

namespace torsion {

namespace {

// ---- the exact tests ----

/// The coordinates left when `axis` is dropped (a projection onto a coordinate plane).
Eigen::Vector2d project(const Eigen::Vector3d& p, int axis) {
  return {p((axis + 1) % 3), p((axis + 2) % 3)};
}

/// Axes in order of decreasing |normal component|: the first whose projection keeps the
/// triangle's area is the plane to decide coplanar questions in (exact coplanar points keep
/// their orientation signs under a projection along an axis the plane is not parallel to).
/// -1 when the triangle has zero area (collinear or coincident corners).
int projectionAxis(const TriangleCorners& t) {
  const Eigen::Vector3d normal = (t[1] - t[0]).cross(t[2] - t[0]).cwiseAbs();
  std::array<int, 3> axes{0, 1, 2};
  std::sort(axes.begin(), axes.end(), [&](int a, int b) { return normal(a) > normal(b); });
  for (int axis : axes)
    if (orient2dSign(project(t[0], axis), project(t[1], axis), project(t[2], axis)) != 0)
      return axis;
  return -1;
}

/// p, collinear with segment ab, lies on it (closed).
bool withinSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return std::min(a(0), b(0)) <= p(0) && p(0) <= std::max(a(0), b(0)) &&
         std::min(a(1), b(1)) <= p(1) && p(1) <= std::max(a(1), b(1));
}

/// Closed segments pq and ab share a point (in the plane).
bool segmentsIntersect2d(const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                         const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const int o1 = orient2dSign(p, q, a), o2 = orient2dSign(p, q, b);
  const int o3 = orient2dSign(a, b, p), o4 = orient2dSign(a, b, q);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && withinSegment(p, q, a)) || (o2 == 0 && withinSegment(p, q, b)) ||
         (o3 == 0 && withinSegment(a, b, p)) || (o4 == 0 && withinSegment(a, b, q));
}

/// p lies in the closed triangle abc (in the plane); false for a triangle of zero area.
bool pointInTriangle2d(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                       const Eigen::Vector2d& c) {
  if (orient2dSign(a, b, c) == 0) return false;
  const int s1 = orient2dSign(a, b, p), s2 = orient2dSign(b, c, p), s3 = orient2dSign(c, a, p);
  const bool positive = s1 > 0 || s2 > 0 || s3 > 0, negative = s1 < 0 || s2 < 0 || s3 < 0;
  return !(positive && negative);
}

/// Two coplanar closed triangles share a point, decided in the coordinate plane along `axis`.
bool coplanarTrianglesIntersect(const TriangleCorners& p, const TriangleCorners& q, int axis) {
  std::array<Eigen::Vector2d, 3> p2, q2;
  for (size_t k = 0; k < 3; ++k) {
    p2[k] = project(p[k], axis);
    q2[k] = project(q[k], axis);
  }
  for (size_t i = 0; i < 3; ++i)
    for (size_t j = 0; j < 3; ++j)
      if (segmentsIntersect2d(p2[i], p2[(i + 1) % 3], q2[j], q2[(j + 1) % 3])) return true;
  return pointInTriangle2d(p2[0], q2[0], q2[1], q2[2]) ||
         pointInTriangle2d(q2[0], p2[0], p2[1], p2[2]);
}

/// The closed segment ab meets the closed triangle t, whose area is not zero (`t_axis` its
/// projectionAxis()).
bool segmentMeetsTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const TriangleCorners& t, int t_axis) {
  const int oa = orient3dSign(t[0], t[1], t[2], a), ob = orient3dSign(t[0], t[1], t[2], b);
  if (oa * ob > 0) return false;  // both strictly on one side
  if (oa == 0 && ob == 0) {       // the segment lies in the triangle's plane
    const Eigen::Vector2d a2 = project(a, t_axis), b2 = project(b, t_axis);
    std::array<Eigen::Vector2d, 3> t2;
    for (size_t k = 0; k < 3; ++k)
      t2[k] = project(t[k], t_axis);
    if (pointInTriangle2d(a2, t2[0], t2[1], t2[2])) return true;
    for (size_t k = 0; k < 3; ++k)
      if (segmentsIntersect2d(a2, b2, t2[k], t2[(k + 1) % 3])) return true;
    return false;
  }
  // The line ab crosses the plane once, within the segment; the crossing lies in the closed
  // triangle iff the line passes no edge on the outside: the three signs never disagree.
  const int s1 = orient3dSign(a, b, t[0], t[1]), s2 = orient3dSign(a, b, t[1], t[2]),
            s3 = orient3dSign(a, b, t[2], t[0]);
  const bool positive = s1 > 0 || s2 > 0 || s3 > 0, negative = s1 < 0 || s2 < 0 || s3 < 0;
  return !(positive && negative);
}

/// +1 / -1 when every corner of `q` lies strictly on one side of `p`'s plane, 0 when all lie in
/// it, 2 otherwise.
int sideOfPlane(const TriangleCorners& p, const TriangleCorners& q) {
  int positive = 0, negative = 0;
  for (const Eigen::Vector3d& corner : q) {
    const int s = orient3dSign(p[0], p[1], p[2], corner);
    positive += s > 0;
    negative += s < 0;
  }
  if (positive == 3) return 1;
  if (negative == 3) return -1;
  if (positive == 0 && negative == 0) return 0;
  return 2;
}

// ---- the search ----

struct Box {
  Eigen::Vector3d lo, hi;
  bool overlaps(const Box& other) const {  // closed: touching boxes overlap
    return (lo.array() <= other.hi.array()).all() && (other.lo.array() <= hi.array()).all();
  }
};

Box boxOf(const TriangleCorners& t) {
  return {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])};
}

/// A bounding-volume tree over fixed boxes, built once by median splits along the widest axis of
/// the box centres. Box coordinates are the triangles' own doubles, so no overlap is lost.
class BoxTree {
 public:
  explicit BoxTree(std::vector<Box> boxes) : boxes_(std::move(boxes)), order_(boxes_.size()) {
    std::iota(order_.begin(), order_.end(), 0);
    if (!boxes_.empty()) build(0, static_cast<int>(boxes_.size()));
  }

  /// Calls visit(i) for every box i overlapping `box`.
  template <class Visit>
  void forEachOverlap(const Box& box, Visit&& visit) const {
    if (nodes_.empty()) return;
    std::vector<int> stack{0};
    while (!stack.empty()) {
      const Node& node = nodes_[static_cast<size_t>(stack.back())];
      stack.pop_back();
      if (!node.box.overlaps(box)) continue;
      if (node.left < 0) {
        for (int k = node.begin; k < node.end; ++k)
          if (boxes_[static_cast<size_t>(order_[static_cast<size_t>(k)])].overlaps(box))
            visit(order_[static_cast<size_t>(k)]);
      } else {
        stack.push_back(node.left);
        stack.push_back(node.right);
      }
    }
  }

 private:
  struct Node {
    Box box;
    int begin = 0, end = 0;     ///< the boxes order_[begin, end) under this node
    int left = -1, right = -1;  ///< children, or -1 for a leaf
  };
  static constexpr int kLeafSize = 4;

  int build(int begin, int end) {
    const int index = static_cast<int>(nodes_.size());
    Box bounds = boxes_[static_cast<size_t>(order_[static_cast<size_t>(begin)])];
    Box centres{bounds.lo + bounds.hi, bounds.lo + bounds.hi};
    for (int k = begin; k < end; ++k) {
      const Box& b = boxes_[static_cast<size_t>(order_[static_cast<size_t>(k)])];
      bounds = {bounds.lo.cwiseMin(b.lo), bounds.hi.cwiseMax(b.hi)};
      centres = {centres.lo.cwiseMin(b.lo + b.hi), centres.hi.cwiseMax(b.lo + b.hi)};
    }
    Node node;
    node.box = bounds;
    node.begin = begin;
    node.end = end;
    nodes_.push_back(node);
    if (end - begin <= kLeafSize) return index;
    int axis = 0;
    (centres.hi - centres.lo).maxCoeff(&axis);
    const int middle = begin + (end - begin) / 2;
    std::nth_element(order_.begin() + begin, order_.begin() + middle, order_.begin() + end,
                     [&](int a, int b) {
                       const Box& ba = boxes_[static_cast<size_t>(a)];
                       const Box& bb = boxes_[static_cast<size_t>(b)];
                       return ba.lo(axis) + ba.hi(axis) < bb.lo(axis) + bb.hi(axis);
                     });
    const int left = build(begin, middle);
    const int right = build(middle, end);
    nodes_[static_cast<size_t>(index)].left = left;
    nodes_[static_cast<size_t>(index)].right = right;
    return index;
  }

  std::vector<Box> boxes_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
};

TriangleCorners cornersOf(const Triangle& t, const Eigen::VectorXd& positions) {
  return {positions.segment<3>(3 * t[0]), positions.segment<3>(3 * t[1]),
          positions.segment<3>(3 * t[2])};
}

bool shareCorner(const Triangle& a, const Triangle& b) {
  for (int i : a)
    for (int j : b)
      if (i == j) return true;
  return false;
}

}  // namespace

bool trianglesIntersect(const TriangleCorners& p, const TriangleCorners& q) {
  const int p_axis = projectionAxis(p), q_axis = projectionAxis(q);
  if (p_axis < 0 && q_axis < 0) return false;  // two zero-area triangles: not decided (header)
  // Separated by either plane: no point in common.
  const int q_side = p_axis >= 0 ? sideOfPlane(p, q) : 2;
  if (q_side == 1 || q_side == -1) return false;
  const int p_side = q_axis >= 0 ? sideOfPlane(q, p) : 2;
  if (p_side == 1 || p_side == -1) return false;
  if (q_side == 0) return coplanarTrianglesIntersect(p, q, p_axis);
  if (p_side == 0) return coplanarTrianglesIntersect(p, q, q_axis);
  for (size_t k = 0; k < 3; ++k) {
    if (q_axis >= 0 && segmentMeetsTriangle(p[k], p[(k + 1) % 3], q, q_axis)) return true;
    if (p_axis >= 0 && segmentMeetsTriangle(q[k], q[(k + 1) % 3], p, p_axis)) return true;
  }
  return false;
}

bool segmentMeetsTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const TriangleCorners& t) {
  const int axis = projectionAxis(t);
  return axis >= 0 && segmentMeetsTriangle(a, b, t, axis);
}

std::vector<TrianglePair> findSurfaceIntersections(const std::vector<Triangle>& triangles,
                                                   const Eigen::VectorXd& positions) {
  std::vector<TriangleCorners> corners;
  std::vector<Box> boxes;
  corners.reserve(triangles.size());
  boxes.reserve(triangles.size());
  for (const Triangle& t : triangles) {
    corners.push_back(cornersOf(t, positions));
    boxes.push_back(boxOf(corners.back()));
  }
  const BoxTree tree(boxes);
  std::vector<TrianglePair> found;
  std::vector<int> partners;
  for (size_t i = 0; i < triangles.size(); ++i) {
    partners.clear();
    tree.forEachOverlap(boxes[i], [&](int j) {
      if (static_cast<size_t>(j) > i) partners.push_back(j);
    });
    std::sort(partners.begin(), partners.end());
    for (int j : partners) {
      const auto u = static_cast<size_t>(j);
      if (shareCorner(triangles[i], triangles[u])) continue;
      if (trianglesIntersect(corners[i], corners[u])) found.push_back({static_cast<int>(i), j});
    }
  }
  return found;
}

std::vector<TrianglePair> findSurfaceIntersections(const std::vector<Triangle>& triangles_a,
                                                   const Eigen::VectorXd& positions_a,
                                                   const std::vector<Triangle>& triangles_b,
                                                   const Eigen::VectorXd& positions_b) {
  std::vector<TriangleCorners> corners_b;
  std::vector<Box> boxes_b;
  corners_b.reserve(triangles_b.size());
  boxes_b.reserve(triangles_b.size());
  for (const Triangle& t : triangles_b) {
    corners_b.push_back(cornersOf(t, positions_b));
    boxes_b.push_back(boxOf(corners_b.back()));
  }
  const BoxTree tree(boxes_b);
  std::vector<TrianglePair> found;
  std::vector<int> partners;
  for (size_t i = 0; i < triangles_a.size(); ++i) {
    const TriangleCorners a = cornersOf(triangles_a[i], positions_a);
    partners.clear();
    tree.forEachOverlap(boxOf(a), [&](int j) { partners.push_back(j); });
    std::sort(partners.begin(), partners.end());
    for (int j : partners)
      if (trianglesIntersect(a, corners_b[static_cast<size_t>(j)]))
        found.push_back({static_cast<int>(i), j});
  }
  return found;
}

}  // namespace torsion
