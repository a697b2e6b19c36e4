#pragma once
// Does a surface pass through itself or through another one? An exact answer, for checking
// contact after the fact (the self-contact and FEM-FEM contact solves prevent crossings only up to
// their tolerances and linearisations; this is the referee).
//
// Two triangles intersect when their closed point sets share a point: crossing, touching at a
// corner or along an edge, or overlapping in one plane. Decided from the signs of exact
// orientation predicates (exact_predicates.h), never from a tolerance:
//   - not coplanar: they intersect iff an edge of one meets the other (their intersection is a
//     segment on the line where the planes meet, and its ends lie on edges);
//   - coplanar: in the plane of the coordinate axes most nearly parallel to them, iff an edge of
//     one meets an edge of the other or a corner of one lies in the other.
// A zero-area triangle takes part through its edges. Inputs are doubles; coordinates must be
// finite (see exact_predicates.h for the range).
//
// The surface searches test every pair of triangles whose axis-aligned boxes overlap, the boxes
// held in a bounding-volume tree built for the call. Within one surface, triangles that share a
// corner (node index) are adjacent and skipped: they always touch.
//
// Usage:
//   const TetMesh& mesh = body->model().mesh();
//   std::vector<TrianglePair> crossings =
//       findSurfaceIntersections(mesh.surfaceTriangles(), body->state().positions);

#include <Eigen/Core>
#include <array>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

using TriangleCorners = std::array<Eigen::Vector3d, 3>;

/// Whether the closed triangles p and q share a point (exact).
bool trianglesIntersect(const TriangleCorners& p, const TriangleCorners& q);

/// Whether the closed segment ab shares a point with the closed triangle t (exact; a segment in
/// the triangle's plane included). A zero-area triangle meets nothing.
bool segmentMeetsTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                          const TriangleCorners& t);

/// Two intersecting triangles, by their indices in the list(s) searched.
struct TrianglePair {
  int first = 0;   ///< the triangle in the (first) list
  int second = 0;  ///< the triangle in the same list (first < second) or in the second list
  bool operator==(const TrianglePair& other) const {
    return first == other.first && second == other.second;
  }
};

/// Every pair of `triangles` that share no corner and intersect, at `positions` (3n, the nodes
/// the triangles index), ordered by first, then second, with first < second.
std::vector<TrianglePair> findSurfaceIntersections(const std::vector<Triangle>& triangles,
                                                   const Eigen::VectorXd& positions);

/// Every intersecting pair (a triangle of `triangles_a` at `positions_a`, one of `triangles_b` at
/// `positions_b`): two surfaces with their own node numbering, e.g. two bodies. Ordered by first,
/// then second.
std::vector<TrianglePair> findSurfaceIntersections(const std::vector<Triangle>& triangles_a,
                                                   const Eigen::VectorXd& positions_a,
                                                   const std::vector<Triangle>& triangles_b,
                                                   const Eigen::VectorXd& positions_b);

}  // namespace torsion
