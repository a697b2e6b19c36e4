#pragma once
// The narrow phase of contact between FEM surfaces, shared by self-contact (self_contact.h) and
// contact between two FEM bodies (body_pair_contact.h): is a (node, triangle) or an (edge, edge)
// pair a candidate along the step's predicted motion, and with which normal, gap and weights
// (docs/contact.md, "Self-contact", "Candidates"). Pure functions of positions: the caller brings
// the broad phase (surface_tree.h), the pairs it never wants (a node's one-ring, edges sharing a
// node), its own exclusion rule and what was held last step.
//
// Positions come as the start of the step (index 0) and the predicted end (index 1); the path is
// linear in between, x(s) = x0 + s (x1 - x0), s in [0, 1].

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <optional>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// A node's projection within this of a triangle's edge (barycentric units) still counts as on
/// the triangle: a node passing exactly over an edge is caught by both triangles (one is kept).
/// Shared by node-face candidates, FEM-FEM pairs and self-contact.
inline constexpr double kFaceInsideTolerance = 0.05;

/// Surface edges of a triangle list, each once, and the edges of every triangle.
struct SurfaceEdges {
  std::vector<std::array<int, 2>> edges;         ///< corners ascending, sorted
  std::vector<std::vector<int>> triangle_edges;  ///< the three edges of each triangle
  /// The (up to) two triangles on each edge, -1 for none.
  std::vector<std::array<int, 2>> edge_triangles;

  explicit SurfaceEdges(const std::vector<Triangle>& triangles);
  /// Unit mean outward normal of the triangles on edge `edge` at positions x (3n), zero if none.
  Eigen::Vector3d outwardNormal(int edge, const std::vector<Triangle>& triangles,
                                const Eigen::VectorXd& x) const;
  /// Cosine of the angle between the unit normals of the two triangles on edge `edge` at x: 1
  /// on a flat surface, 0 at a right-angled ridge or valley; -1 for an edge of one triangle.
  double foldCosine(int edge, const std::vector<Triangle>& triangles,
                    const Eigen::VectorXd& x) const;
};

/// Distances and tolerances that decide a candidate.
struct CandidateRules {
  double margin = 0;  ///< m: within this now, or at the end of the path, is a candidate
  /// A node (edge) this fraction of the triangle's shortest edge (its own length) behind is on the
  /// far side of the body, not through the surface.
  double max_depth = 0.25;
  /// m: a pair not held last step and behind by more than this at the start is refused (a node
  /// across a sharp convex crease, or edges crossed before).
  double crease_depth = 0;
};

/// Barycentric coordinates of p's projection onto the plane of (a, b, c) (unclamped).
Eigen::Vector3d projectionWeights(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// A node-triangle candidate: the constraint's normal and gap at the step's start, when on the
/// path it was judged, and the node's projection there.
struct NodeTriangleHit {
  Eigen::Vector3d normal;   ///< unit, the triangle's (right-handed) normal at the start
  double gap = 0;           ///< m, the node's signed distance along it at the start
  double when = 0;          ///< s in [0, 1] where the node meets the plane (0: within the margin)
  Eigen::Vector3d weights;  ///< barycentric coordinates of the projection at `when` (unclamped)
};

/// A pair's own exclusion rule, asked after the geometric tests of a pair not held last step,
/// with the triangle's normal and the node's gap at the start: true refuses the pair.
using ExclusionRule = std::function<bool(const Eigen::Vector3d& normal, double gap)>;

/// Node p against triangle (a, b, c): a candidate when the triangle has a plane, the node is not
/// deeper than max_depth behind it, not behind by more than crease_depth unless `held`, not
/// refused by `excluded` (unless `held`; empty: no rule), and its projection falls inside the
/// triangle (5 % barycentric slack) at the moment of the path where it meets the plane: now if
/// within the margin, at the crossing if it passes through, at the end if it ends within the
/// margin.
std::optional<NodeTriangleHit> nodeTriangleCandidate(
    const std::array<Eigen::Vector3d, 2>& p, const std::array<Eigen::Vector3d, 3>& triangle0,
    const std::array<Eigen::Vector3d, 3>& triangle1, const CandidateRules& rules, bool held,
    const ExclusionRule& excluded);

/// Closest points of the lines a + u (b - a) and c + v (d - c); false when (nearly) parallel
/// (then u, v and distance are untouched).
bool closestPointsOfLines(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const Eigen::Vector3d& c, const Eigen::Vector3d& d, double& u, double& v,
                          double& distance);

/// An edge-edge candidate: edge e = (e0, e1) against f = (f0, f1), the constraint's weights
/// beta = (1 - u, u, -(1 - v), -v) on (e0, e1, f0, f1).
struct EdgeEdgeHit {
  Eigen::Vector3d normal;  ///< unit, e x f oriented from f's surface into e's, at the start
  double gap = 0;          ///< m, e's distance from f along it at the start (signed)
  double u = 0, v = 0;     ///< the closest points' parameters on e and f when judged
};

/// Edge e against edge f, positions at the start (e[0], f[0]: both corners) and predicted end.
/// A candidate when the edges are not nearly parallel (nodes and faces hold those), their lines'
/// closest points lie inside both edges at the moment of the path where they meet (now if within
/// the margin, at the crossing, or at the end if within the margin), their surfaces face each
/// other (`outward()`: f's triangles' mean outward normal minus e's; asked only then), not
/// behind by more than crease_depth unless held, nor max_depth of e's length, nor refused by
/// `excluded` (oriented normal and gap; unless held; empty: no rule). `held()`: the multiplier
/// the pair ended last step with (nullptr: not held); its direction then orients the normal
/// instead.
std::optional<EdgeEdgeHit> edgeEdgeCandidate(const std::array<std::array<Eigen::Vector3d, 2>, 2>& e,
                                             const std::array<std::array<Eigen::Vector3d, 2>, 2>& f,
                                             const CandidateRules& rules,
                                             const std::function<const Eigen::Vector3d*()>& held,
                                             const std::function<Eigen::Vector3d()>& outward,
                                             const ExclusionRule& excluded);

}  // namespace torsion
