#pragma once
// The hand plane's contact patch (docs/design.md section 3; the report's Algorithm 1, done right),
// as pure functions of a mesh and its current node positions.
//
// A hand is a frame (O, R = [i j k]). Its plane passes through O, spanned by i and j (normal k).
// The hand holds the connected patch of boundary-surface triangles that the plane cuts and that
// the ray from O along +i reaches first:
//   1. every surface triangle the plane cuts is a candidate (triangleCutByPlane);
//   2. the ray O + t i, t >= 0, is tested against every candidate (Moller-Trumbore); the candidate
//      with the smallest t is the seed;
//   3. a flood fill from the seed over edge-adjacent surface triangles (TetMesh::
//      surfaceTriangleNeighbours) that the plane also cuts, each visited once, gives the patch.
// The report's pseudocode neither tests neighbours against the plane nor marks them visited; this
// does both, so a body with several branches (a U, the dragon) gives only the branch the ray hits.
//
// Vertices on the plane. A vertex v is on the plane when |k.(v - O)| <= 1e-12 |k| |v - O| (round
// off of the dot product and of a rotated frame), and such a vertex counts as being on the
// POSITIVE side (+k). A triangle is cut when it has at least one vertex strictly on the negative
// side and at least one on the closed positive side. This is the plane moved by an infinitesimal
// amount along -k: every vertex gets one side, the same in every triangle that shares it, so the
// cut triangles always form the band(s) a nearby generic plane would cut, never two bands, never
// none. Consequences:
//   - a plane through a layer of nodes (a cylinder's ring at z = c, k = +z) cuts the one band of
//     triangles just below the layer (same as the plane z = c - epsilon);
//   - a triangle touching the plane at a vertex or an edge is cut when its other vertices lie on
//     the negative side, not when they lie on the positive side; a triangle lying in the plane is
//     not cut;
//   - a plane lying on a flat face of the body (a cylinder's end cap) cuts the band of triangles
//     next to that face when k points out of the body across the face (it grabs the rim and the
//     ring below it, not the face's interior nodes), and nothing when k points into the body.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "torsion/constraints/frame.h"
#include "torsion/mesh/tet_mesh.h"

namespace torsion {

/// Relative tolerance under which a vertex counts as on the plane (see the file comment).
inline constexpr double kOnPlaneRelativeTolerance = 1e-12;

/// True when p is on the closed positive side of the plane through `origin` with normal `normal`
/// (need not be unit): normal.(p - origin) >= -kOnPlaneRelativeTolerance |normal| |p - origin|.
bool onPositiveSide(const Eigen::Vector3d& p, const Eigen::Vector3d& origin,
                    const Eigen::Vector3d& normal);

/// True when the plane cuts the triangle (a, b, c): at least one vertex strictly on the negative
/// side and at least one on the closed positive side (onPositiveSide). See the file comment.
bool triangleCutByPlane(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c, const Eigen::Vector3d& origin,
                        const Eigen::Vector3d& normal);

/// Moller-Trumbore: the parameter t >= 0 at which the ray origin + t direction meets the triangle
/// (a, b, c), or nothing. The triangle's edges and vertices count as inside, with a relative
/// tolerance of 1e-9 on the barycentric coordinates, so a ray through a shared edge or vertex
/// hits every triangle around it (a ray lying in the cut plane often passes exactly through
/// mesh edges and vertices). A ray parallel to the triangle's plane never hits it.
std::optional<double> rayHitsTriangle(const Eigen::Vector3d& origin,
                                      const Eigen::Vector3d& direction, const Eigen::Vector3d& a,
                                      const Eigen::Vector3d& b, const Eigen::Vector3d& c);

enum class HandSelectionStatus {
  kGrabbed,        ///< the patch is not empty
  kNoTriangleCut,  ///< the plane misses the body
  kRayMissed,      ///< the plane cuts the body, but the ray from O along i hits none of the cut
                   ///< triangles (e.g. O outside, i pointing away)
};
const char* toString(HandSelectionStatus status);

struct HandSelection {
  HandSelectionStatus status = HandSelectionStatus::kNoTriangleCut;
  std::string message;         ///< for the user: what was grabbed, or why nothing was
  int cut_triangle_count = 0;  ///< surface triangles the plane cuts, in any branch
  int hit_triangle = -1;       ///< the seed: the first cut triangle along the ray (or -1)
  double hit_distance = 0;     ///< t of the hit, along unit i (m)
  Eigen::Vector3d hit_point = Eigen::Vector3d::Zero();  ///< O + t i
  std::vector<int> triangles;  ///< the patch: surface triangle indices, ascending (empty unless
                               ///< kGrabbed)
  std::vector<int> nodes;      ///< the patch's vertices, ascending, unique: the grabbed nodes
};

/// The hand's contact patch for the frame (O = frame.origin, i, j, k = columns of
/// frame.rotation) at `positions` (3n, the body's current node positions, world coordinates).
/// Nothing is grabbed unless status is kGrabbed. O(surface triangles) plus the patch's size.
HandSelection selectGrabbedPatch(const TetMesh& mesh, const Eigen::VectorXd& positions,
                                 const Frame& frame);

}  // namespace torsion
