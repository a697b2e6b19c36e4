#pragma once
// The immutable description of a tetrahedral mesh: rest positions, tets and the boundary surface
// derived from them. Indices, not pointers, so it can be copied, shared between bodies and
// handed to worker threads. Built (and validated) by buildTetMesh; never modified afterwards.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace torsion {

/// Four node indices. Positive orientation: (x1-x0) . ((x2-x0) x (x3-x0)) > 0.
using Tet = std::array<int, 4>;
/// Three node indices, counter-clockwise seen from outside the body (normal points outward).
using Triangle = std::array<int, 3>;

/// Compressed rows: the items of row r are items[offsets[r] .. offsets[r+1]).
struct CompressedRows {
  std::vector<int> offsets{0};
  std::vector<int> items;

  int rowCount() const { return static_cast<int>(offsets.size()) - 1; }
  int rowBegin(int r) const { return offsets[static_cast<size_t>(r)]; }
  int rowEnd(int r) const { return offsets[static_cast<size_t>(r) + 1]; }
};

class TetMesh {
 public:
  TetMesh() = default;

  /// Assembles the derived data (surface, adjacency, incidence) from validated, positively
  /// oriented tets. Use buildTetMesh to get validation and error messages; this constructor
  /// asserts on bad input.
  TetMesh(std::vector<Eigen::Vector3d> rest_positions, std::vector<Tet> tets);

  int nodeCount() const { return static_cast<int>(rest_positions_.size()); }
  int tetCount() const { return static_cast<int>(tets_.size()); }
  int surfaceTriangleCount() const { return static_cast<int>(surface_triangles_.size()); }

  /// Rest positions in metres.
  const std::vector<Eigen::Vector3d>& restPositions() const { return rest_positions_; }
  const std::vector<Tet>& tets() const { return tets_; }

  /// Boundary faces: faces that belong to exactly one tet, oriented outward.
  const std::vector<Triangle>& surfaceTriangles() const { return surface_triangles_; }
  /// The tet that owns each surface triangle.
  const std::vector<int>& surfaceTriangleTets() const { return surface_triangle_tets_; }
  /// Surface triangles sharing an edge with each surface triangle (usually 3; more on
  /// non-manifold edges, fewer never for a closed surface). Row t lists neighbours of triangle t.
  const CompressedRows& surfaceTriangleNeighbours() const { return surface_neighbours_; }
  /// Nodes on the boundary surface, sorted ascending.
  const std::vector<int>& surfaceNodes() const { return surface_nodes_; }
  /// Tets incident to each node. Row n lists the tets that contain node n, ascending.
  const CompressedRows& nodeTets() const { return node_tets_; }

  /// Signed volume of tet t at rest (positive for every tet of a built mesh), m^3.
  double restVolume(int t) const;
  /// Sum of rest volumes, m^3.
  double totalRestVolume() const;
  /// Axis-aligned bounds of the rest positions.
  Eigen::Vector3d boundsMin() const;
  Eigen::Vector3d boundsMax() const;

 private:
  std::vector<Eigen::Vector3d> rest_positions_;
  std::vector<Tet> tets_;
  std::vector<Triangle> surface_triangles_;
  std::vector<int> surface_triangle_tets_;
  CompressedRows surface_neighbours_;
  std::vector<int> surface_nodes_;
  CompressedRows node_tets_;
};

/// 6 x signed volume of the tet (a,b,c,d): (b-a) . ((c-a) x (d-a)).
double sixSignedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d);

}  // namespace torsion
