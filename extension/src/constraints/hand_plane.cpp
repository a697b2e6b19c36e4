#include "torsion/constraints/hand_plane.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <deque>
#include <sstream>

namespace torsion {
namespace {

constexpr double kBarycentricTolerance = 1e-9;
constexpr double kParallelTolerance = 1e-12;

std::string describe(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return out.str();
}

Eigen::Vector3d node(const Eigen::VectorXd& positions, int n) {
  return positions.segment<3>(3 * static_cast<Eigen::Index>(n));
}

}  // namespace

bool onPositiveSide(const Eigen::Vector3d& p, const Eigen::Vector3d& origin,
                    const Eigen::Vector3d& normal) {
  const Eigen::Vector3d d = p - origin;
  return normal.dot(d) >= -kOnPlaneRelativeTolerance * normal.norm() * d.norm();
}

bool triangleCutByPlane(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& normal) {
  const int positive = int{onPositiveSide(a, origin, normal)} +
                       int{onPositiveSide(b, origin, normal)} +
                       int{onPositiveSide(c, origin, normal)};
  return positive > 0 && positive < 3;
}

std::optional<double> rayHitsTriangle(const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& direction, const Eigen::Vector3d& a,
                                      const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a;
  const Eigen::Vector3d e2 = c - a;
  const Eigen::Vector3d p = direction.cross(e2);
  const double det = e1.dot(p);
  // det = direction . (e2 x e1): |det| / (|d| |e1| |e2|) is the sine of the ray-plane angle times
  // the sine of the triangle's angle at a.
  if (!(std::abs(det) > kParallelTolerance * direction.norm() * e1.norm() * e2.norm()))
    return std::nullopt;
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = origin - a;
  const double u = s.dot(p) * inv;
  if (u < -kBarycentricTolerance || u > 1 + kBarycentricTolerance) return std::nullopt;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = direction.dot(q) * inv;
  if (v < -kBarycentricTolerance || u + v > 1 + kBarycentricTolerance) return std::nullopt;
  const double t = e2.dot(q) * inv;
  if (!(t >= 0)) return std::nullopt;
  return t;
}

const char* toString(HandSelectionStatus status) {
  switch (status) {
    case HandSelectionStatus::kGrabbed:
      return "grabbed";
    case HandSelectionStatus::kNoTriangleCut:
      return "no triangle cut";
    case HandSelectionStatus::kRayMissed:
      return "ray missed";
  }
  return "?";
}

HandSelection selectGrabbedPatch(const TetMesh& mesh, const Eigen::VectorXd& positions,
                                 const Frame& frame) {
  assert(positions.size() == 3 * static_cast<Eigen::Index>(mesh.nodeCount()));
  const Eigen::Matrix3d rotation = frame.rotation.normalized().toRotationMatrix();
  const Eigen::Vector3d origin = frame.origin;
  const Eigen::Vector3d i = rotation.col(0);
  const Eigen::Vector3d k = rotation.col(2);
  const std::vector<Triangle>& triangles = mesh.surfaceTriangles();
  const int triangle_count = mesh.surfaceTriangleCount();

  HandSelection selection;
  const std::string where = "hand plane through " + describe(origin) + " with normal " +
                            describe(k) + " and ray along " + describe(i);

  // 1. Every surface triangle the plane cuts. Vertex sides are evaluated per triangle from the
  // same positions with the same arithmetic, so a shared vertex gets the same side everywhere.
  std::vector<char> cut(static_cast<size_t>(triangle_count), 0);
  std::vector<int> candidates;
  for (int t = 0; t < triangle_count; ++t) {
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    if (triangleCutByPlane(node(positions, tri[0]), node(positions, tri[1]),
                           node(positions, tri[2]), origin, k)) {
      cut[static_cast<size_t>(t)] = 1;
      candidates.push_back(t);
    }
  }
  selection.cut_triangle_count = static_cast<int>(candidates.size());
  if (candidates.empty()) {
    selection.status = HandSelectionStatus::kNoTriangleCut;
    selection.message = where + ": the plane cuts no surface triangle of the body";
    return selection;
  }

  // 2. The first cut triangle along the ray from O along +i (ties: the lowest index).
  for (int t : candidates) {
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    const std::optional<double> hit = rayHitsTriangle(
        origin, i, node(positions, tri[0]), node(positions, tri[1]), node(positions, tri[2]));
    if (hit && (selection.hit_triangle < 0 || *hit < selection.hit_distance)) {
      selection.hit_triangle = t;
      selection.hit_distance = *hit;
    }
  }
  if (selection.hit_triangle < 0) {
    selection.status = HandSelectionStatus::kRayMissed;
    selection.message = where + ": the plane cuts " + std::to_string(candidates.size()) +
                        " surface triangles but the ray hits none of them";
    return selection;
  }
  selection.hit_point = origin + selection.hit_distance * i;

  // 3. Flood fill over edge-adjacent cut triangles, each visited once.
  const CompressedRows& neighbours = mesh.surfaceTriangleNeighbours();
  std::vector<char> visited(static_cast<size_t>(triangle_count), 0);
  std::deque<int> queue{selection.hit_triangle};
  visited[static_cast<size_t>(selection.hit_triangle)] = 1;
  while (!queue.empty()) {
    const int t = queue.front();
    queue.pop_front();
    selection.triangles.push_back(t);
    for (int r = neighbours.rowBegin(t); r < neighbours.rowEnd(t); ++r) {
      const int n = neighbours.items[static_cast<size_t>(r)];
      if (cut[static_cast<size_t>(n)] && !visited[static_cast<size_t>(n)]) {
        visited[static_cast<size_t>(n)] = 1;
        queue.push_back(n);
      }
    }
  }
  std::sort(selection.triangles.begin(), selection.triangles.end());
  for (int t : selection.triangles) {
    const Triangle& tri = triangles[static_cast<size_t>(t)];
    selection.nodes.insert(selection.nodes.end(), tri.begin(), tri.end());
  }
  std::sort(selection.nodes.begin(), selection.nodes.end());
  selection.nodes.erase(std::unique(selection.nodes.begin(), selection.nodes.end()),
                        selection.nodes.end());

  selection.status = HandSelectionStatus::kGrabbed;
  selection.message =
      where + ": grabbed " + std::to_string(selection.nodes.size()) + " nodes on " +
      std::to_string(selection.triangles.size()) + " of " + std::to_string(candidates.size()) +
      " cut surface triangles (ray hit at t = " + std::to_string(selection.hit_distance) + " m)";
  return selection;
}

}  // namespace torsion
