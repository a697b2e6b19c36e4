#pragma once
// Test helper: do two surface triangles of a body cross each other? A geometric test
// (orientation signs; an edge must leave the other triangle's plane by more than 1e-9 of the
// edge length on both sides, so rounding in nearly coplanar neighbours, e.g. facets of one column
// of a cylinder, is no crossing; coplanar overlaps are not detected) over every pair of surface
// triangles that share no corner, the pairs found by the surface tree's boxes. Used to check that
// self-contact keeps a surface free of self-intersections.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "torsion/contact/surface_tree.h"

namespace torsion {

inline double orient(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                     const Eigen::Vector3d& d) {
  return (b - a).cross(c - a).dot(d - a);
}

/// Whether segment pq passes through the interior of triangle abc (strictly).
inline bool segmentCrossesTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                                   const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                   const Eigen::Vector3d& c) {
  const Eigen::Vector3d normal = (b - a).cross(c - a);
  const double eps = 1e-9 * (q - p).norm() * normal.norm();
  const double sp = normal.dot(p - a), sq = normal.dot(q - a);
  if (!((sp > eps && sq < -eps) || (sp < -eps && sq > eps))) return false;
  const double s1 = orient(p, q, a, b), s2 = orient(p, q, b, c), s3 = orient(p, q, c, a);
  return (s1 > 0 && s2 > 0 && s3 > 0) || (s1 < 0 && s2 < 0 && s3 < 0);
}

/// Number of pairs of surface triangles sharing no corner that cross, at positions x (3n).
inline int countSurfaceIntersections(SurfaceTree& tree, const Eigen::VectorXd& x) {
  tree.refit(x, x, 0.0);
  const std::vector<Triangle>& tris = tree.triangles();
  std::vector<int> found;
  int crossings = 0;
  auto corner = [&](const Triangle& t, int k) -> Eigen::Vector3d {
    return x.segment<3>(3 * t[static_cast<size_t>(k)]);
  };
  for (size_t i = 0; i < tris.size(); ++i) {
    const Triangle& t = tris[i];
    Eigen::Vector3d lo = corner(t, 0), hi = lo;
    for (int k = 1; k < 3; ++k) {
      lo = lo.cwiseMin(corner(t, k));
      hi = hi.cwiseMax(corner(t, k));
    }
    tree.query(lo, hi, found);
    for (int j : found) {
      if (static_cast<size_t>(j) <= i) continue;
      const Triangle& u = tris[static_cast<size_t>(j)];
      bool shared = false;
      for (int a : t)
        for (int b : u)
          shared = shared || a == b;
      if (shared) continue;
      bool cross = false;
      for (int k = 0; k < 3 && !cross; ++k) {
        cross = segmentCrossesTriangle(corner(t, k), corner(t, (k + 1) % 3), corner(u, 0),
                                       corner(u, 1), corner(u, 2)) ||
                segmentCrossesTriangle(corner(u, k), corner(u, (k + 1) % 3), corner(t, 0),
                                       corner(t, 1), corner(t, 2));
      }
      if (cross) ++crossings;
    }
  }
  return crossings;
}

}  // namespace torsion
