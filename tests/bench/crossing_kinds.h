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
};

namespace crossing_kinds_detail {

inline Eigen::Vector3d corner(const Eigen::VectorXd& x, int node) { return x.segment<3>(3 * node); }

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

inline bool hasCorner(const Triangle& t, int node) {
  return t[0] == node || t[1] == node || t[2] == node;
}

}  // namespace crossing_kinds_detail

inline CrossingKinds classifyCrossings(const std::vector<TrianglePair>& pairs,
                                       const std::vector<Triangle>& triangles,
                                       const Eigen::VectorXd& x,
                                       const std::vector<SurfaceContact>& contacts,
                                       double max_depth) {
  using namespace crossing_kinds_detail;
  CrossingKinds kinds;
  for (const TrianglePair& pair : pairs) {
    const Triangle& p = triangles[static_cast<size_t>(pair.first)];
    const Triangle& q = triangles[static_cast<size_t>(pair.second)];
    const double pq = cornerInside(p, q, x), qp = cornerInside(q, p, x);
    const bool edge_edge = pq < 0 && qp < 0;
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
