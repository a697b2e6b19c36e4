#pragma once
// What kind of crossing is each pair of intersecting surface triangles the exact checker
// (analysis/surface_intersections.h) finds, and did this step's self-contact have a candidate for
// it? For benches that diagnose crossings (bench_self_contact, bench_kink_self_contact).
//
// Kinds (two crossing triangles always straddle each other's planes):
//   node in face: a corner of one lies behind the other's plane (against its outward normal) and
//                 projects inside it (5 % barycentric slack, as detection): a node-triangle
//                 constraint can see it. `deep` when that corner is more than `max_depth` of the
//                 triangle's shortest edge behind (detection's far-side rule refuses it).
//   edge-edge:    no corner projects inside the other triangle from behind: the triangles cross
//                 through their edges, and only an edge-edge constraint can see it.
// Depth (a proxy for how far apart the pair must move): the inside corner's depth behind the
// other triangle (the shallower side), or for an edge-edge crossing the smallest distance between
// an edge of one and an edge of the other whose closest points lie on both. Pairs no deeper than
// the contact's gap tolerance are counted apart: the solve accepts them (it drives end gaps to
// zero within the tolerance, and the exact checker counts touching as intersecting).
// Candidate: this step's contacts include a node-triangle pair of a corner of one with the other,
// or an edge pair with an edge of each.
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <vector>

#include "torsion/analysis/surface_intersections.h"
#include "torsion/contact/surface_contact_set.h"

namespace torsion {

struct CrossingKinds {
  int node_in_face = 0;       ///< a corner behind the other triangle, projecting inside it
  int node_in_face_deep = 0;  ///< of which beyond max_depth (refused by detection)
  int edge_edge = 0;          ///< no corner inside: edges through each other
  int with_candidate = 0;     ///< pairs this step's contacts cover
  int edge_edge_with_candidate = 0;
  int within_tolerance = 0;  ///< pairs no deeper than the gap tolerance
  double deepest = 0;        ///< m, the deepest pair's depth
};

namespace crossing_kinds_detail {

inline Eigen::Vector3d corner(const Eigen::VectorXd& x, int node) {
  return x.segment<3>(3 * node);
}

// Deepest corner of `p` behind triangle `t` that projects inside it (depth >= 0), or -1.
inline double cornerInside(const Triangle& p, const Triangle& t, const Eigen::VectorXd& x) {
  const Eigen::Vector3d a = corner(x, t[0]), b = corner(x, t[1]), c = corner(x, t[2]);
  Eigen::Vector3d n = (b - a).cross(c - a);
  if (!(n.norm() > 0)) return -1;
  n.normalize();
  double deepest = -1;
  for (int node : p) {
    const Eigen::Vector3d q = corner(x, node);
    const double depth = -n.dot(q - a);
    if (depth < 0) continue;
    const Eigen::Vector3d e0 = b - a, e1 = c - a, d = q - a;
    const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
    const double det = d00 * d11 - d01 * d01;
    const double v = (d11 * d.dot(e0) - d01 * d.dot(e1)) / det;
    const double w = (d00 * d.dot(e1) - d01 * d.dot(e0)) / det;
    if (std::min({1 - v - w, v, w}) >= -0.05) deepest = std::max(deepest, depth);
  }
  return deepest;
}

// Smallest distance between an edge of p and an edge of q whose closest points lie on both.
inline double edgeEdgeDepth(const Triangle& p, const Triangle& q, const Eigen::VectorXd& x) {
  double smallest = 1e300;
  for (size_t i = 0; i < 3; ++i) {
    for (size_t j = 0; j < 3; ++j) {
      const Eigen::Vector3d a = corner(x, p[i]), b = corner(x, p[(i + 1) % 3]);
      const Eigen::Vector3d c = corner(x, q[j]), d = corner(x, q[(j + 1) % 3]);
      const Eigen::Vector3d d1 = b - a, d2 = d - c, w = a - c;
      const double aa = d1.dot(d1), bb = d1.dot(d2), cc = d2.dot(d2);
      const double den = aa * cc - bb * bb;
      if (!(den > 1e-12 * aa * cc)) continue;
      const double u = (bb * d2.dot(w) - cc * d1.dot(w)) / den;
      const double v = (aa * d2.dot(w) - bb * d1.dot(w)) / den;
      if (u < -0.01 || u > 1.01 || v < -0.01 || v > 1.01) continue;
      smallest = std::min(smallest, (a + u * d1 - c - v * d2).norm());
    }
  }
  return smallest;
}

inline bool hasCorner(const Triangle& t, int node) {
  return t[0] == node || t[1] == node || t[2] == node;
}

}  // namespace crossing_kinds_detail

inline CrossingKinds classifyCrossings(const std::vector<TrianglePair>& pairs,
                                       const std::vector<Triangle>& triangles,
                                       const Eigen::VectorXd& x,
                                       const std::vector<SurfaceContact>& contacts,
                                       double max_depth, double tolerance) {
  using namespace crossing_kinds_detail;
  CrossingKinds kinds;
  for (const TrianglePair& pair : pairs) {
    const Triangle& p = triangles[static_cast<size_t>(pair.first)];
    const Triangle& q = triangles[static_cast<size_t>(pair.second)];
    const double pq = cornerInside(p, q, x), qp = cornerInside(q, p, x);
    const bool edge_edge = pq < 0 && qp < 0;
    const double depth =
        edge_edge ? edgeEdgeDepth(p, q, x) : std::min(pq < 0 ? 1e300 : pq, qp < 0 ? 1e300 : qp);
    if (depth <= tolerance) ++kinds.within_tolerance;
    if (depth < 1e300) kinds.deepest = std::max(kinds.deepest, depth);
    if (edge_edge) {
      ++kinds.edge_edge;
    } else {
      ++kinds.node_in_face;
      auto shortest = [&](const Triangle& t) {
        double s = 1e300;
        for (size_t k = 0; k < 3; ++k)
          s = std::min(s, (corner(x, t[k]) - corner(x, t[(k + 1) % 3])).norm());
        return s;
      };
      if ((pq < 0 || pq > max_depth * shortest(q)) && (qp < 0 || qp > max_depth * shortest(p)))
        ++kinds.node_in_face_deep;
    }
    bool covered = false;
    for (const SurfaceContact& c : contacts) {
      if (c.edge < 0) {
        covered = (c.triangle == pair.second && hasCorner(p, c.nodes[0])) ||
                  (c.triangle == pair.first && hasCorner(q, c.nodes[0]));
      } else {
        const bool e_in_p = hasCorner(p, c.nodes[0]) && hasCorner(p, c.nodes[1]);
        const bool e_in_q = hasCorner(q, c.nodes[0]) && hasCorner(q, c.nodes[1]);
        const bool f_in_p = hasCorner(p, c.nodes[2]) && hasCorner(p, c.nodes[3]);
        const bool f_in_q = hasCorner(q, c.nodes[2]) && hasCorner(q, c.nodes[3]);
        covered = (e_in_p && f_in_q) || (e_in_q && f_in_p);
      }
      if (covered) break;
    }
    if (covered) ++kinds.with_candidate;
    if (covered && edge_edge) ++kinds.edge_edge_with_candidate;
  }
  return kinds;
}

}  // namespace torsion
