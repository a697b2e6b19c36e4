#pragma once
// Test helper: how deep is a point inside a body's closed surface? The generalised winding number
// (Van Oosterom & Strackee's solid angle of each triangle, summed over 4 pi) says inside (1) or
// outside (0) robustly for any shape, with no ray to graze an edge; inside, the depth is the
// distance to the nearest surface triangle. Used to check that no node of one body ends up in
// another (tests/scene/fast_impact_test.cpp, tests/contact/body_contact_test.cpp).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

inline constexpr double kPi = 3.14159265358979323846;

// The closed surface of a body at positions x (3n).
struct ClosedSurface {
  const std::vector<Triangle>* triangles;
  const Eigen::VectorXd* x;
  Eigen::Vector3d corner(const Triangle& t, int k) const {
    return x->segment<3>(3 * t[static_cast<size_t>(k)]);
  }
};

// Generalised winding number of the surface around p (Van Oosterom & Strackee's solid angle of
// each triangle, summed over 4 pi): 1 inside a closed outward-oriented surface, 0 outside, robust
// to any shape (no ray to graze an edge).
inline double windingNumber(const ClosedSurface& s, const Eigen::Vector3d& p) {
  double sum = 0;
  for (const Triangle& t : *s.triangles) {
    const Eigen::Vector3d a = s.corner(t, 0) - p, b = s.corner(t, 1) - p, c = s.corner(t, 2) - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2 * std::atan2(numerator, denominator);
  }
  return sum / (4 * kPi);
}

// Distance from p to the triangle (a, b, c) (Ericson, Real-Time Collision Detection 5.1.5).
inline double distanceToTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                 const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.norm();
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.norm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return (p - (a + d1 / (d1 - d3) * ab)).norm();
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.norm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return (p - (a + d2 / (d2 - d6) * ac)).norm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return (p - (b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b))).norm();
  const double denominator = 1 / (va + vb + vc);
  return (p - (a + ab * (vb * denominator) + ac * (vc * denominator))).norm();
}

// Depth of p inside the closed surface: its distance to the surface when the winding number says
// inside, else 0.
inline double depthInSurface(const ClosedSurface& s, const Eigen::Vector3d& p) {
  if (windingNumber(s, p) < 0.5) return 0;
  double nearest = std::numeric_limits<double>::infinity();
  for (const Triangle& t : *s.triangles)
    nearest =
        std::min(nearest, distanceToTriangle(p, s.corner(t, 0), s.corner(t, 1), s.corner(t, 2)));
  return nearest;
}

/// The deepest of `mesh`'s surface nodes (at positions xn) inside `other`'s closed surface (at
/// positions xo), m; 0 when none is inside.
inline double deepestNodeInside(const TetMesh& mesh, const Eigen::VectorXd& xn,
                                const TetMesh& other, const Eigen::VectorXd& xo) {
  const ClosedSurface surface{&other.surfaceTriangles(), &xo};
  double deepest = 0;
  for (int p : mesh.surfaceNodes())
    deepest = std::max(deepest, depthInSurface(surface, xn.segment<3>(3 * p)));
  return deepest;
}

}  // namespace torsion
