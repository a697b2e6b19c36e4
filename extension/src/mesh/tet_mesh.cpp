#include "torsion/mesh/tet_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cassert>
#include <numeric>
#include <tuple>

#include "tet_faces.h"

namespace torsion {

namespace {

struct EdgeRecord {
  int a, b;  // a < b
  int triangle;
  bool operator<(const EdgeRecord& o) const {
    return std::tie(a, b, triangle) < std::tie(o.a, o.b, o.triangle);
  }
};

CompressedRows rowsFromPairs(int row_count, std::vector<std::pair<int, int>> pairs) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  CompressedRows rows;
  rows.offsets.assign(static_cast<size_t>(row_count) + 1, 0);
  rows.items.reserve(pairs.size());
  for (const auto& [row, item] : pairs) {
    ++rows.offsets[static_cast<size_t>(row) + 1];
    rows.items.push_back(item);
  }
  std::partial_sum(rows.offsets.begin(), rows.offsets.end(), rows.offsets.begin());
  return rows;
}

}  // namespace

namespace detail {
std::vector<FaceRecord> sortedFaces(const std::vector<Tet>& tets) {
  std::vector<FaceRecord> faces;
  faces.reserve(tets.size() * 4);
  for (size_t t = 0; t < tets.size(); ++t) {
    for (int f = 0; f < 4; ++f) {
      std::array<int, 3> key = {tets[t][static_cast<size_t>(kOutwardFaces[f][0])],
                                tets[t][static_cast<size_t>(kOutwardFaces[f][1])],
                                tets[t][static_cast<size_t>(kOutwardFaces[f][2])]};
      std::sort(key.begin(), key.end());
      faces.push_back({key, static_cast<int>(t), f});
    }
  }
  std::sort(faces.begin(), faces.end(), [](const FaceRecord& a, const FaceRecord& b) {
    return std::tie(a.key, a.tet, a.local_face) < std::tie(b.key, b.tet, b.local_face);
  });
  return faces;
}
}  // namespace detail

double sixSignedVolume(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                       const Eigen::Vector3d& d) {
  return (b - a).dot((c - a).cross(d - a));
}

TetMesh::TetMesh(std::vector<Eigen::Vector3d> rest_positions, std::vector<Tet> tets)
    : rest_positions_(std::move(rest_positions)), tets_(std::move(tets)) {
  const int node_count = nodeCount();

  // Boundary faces are the faces that appear in exactly one tet.
  const std::vector<detail::FaceRecord> faces = detail::sortedFaces(tets_);
  for (size_t i = 0; i < faces.size();) {
    size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key)
      ++j;
    if (j - i == 1) {
      const Tet& tet = tets_[static_cast<size_t>(faces[i].tet)];
      const int* local = detail::kOutwardFaces[faces[i].local_face];
      surface_triangles_.push_back({tet[static_cast<size_t>(local[0])],
                                    tet[static_cast<size_t>(local[1])],
                                    tet[static_cast<size_t>(local[2])]});
      surface_triangle_tets_.push_back(faces[i].tet);
    }
    assert(j - i <= 2 && "a face shared by more than two tets: validate with buildTetMesh");
    i = j;
  }

  // Surface triangles are neighbours when they share an edge.
  std::vector<EdgeRecord> edges;
  edges.reserve(surface_triangles_.size() * 3);
  for (int t = 0; t < surfaceTriangleCount(); ++t) {
    const Triangle& tri = surface_triangles_[static_cast<size_t>(t)];
    for (int e = 0; e < 3; ++e) {
      int a = tri[static_cast<size_t>(e)];
      int b = tri[static_cast<size_t>((e + 1) % 3)];
      edges.push_back({std::min(a, b), std::max(a, b), t});
    }
  }
  std::sort(edges.begin(), edges.end());
  std::vector<std::pair<int, int>> neighbour_pairs;
  for (size_t i = 0; i < edges.size();) {
    size_t j = i + 1;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b)
      ++j;
    for (size_t p = i; p < j; ++p) {
      for (size_t q = i; q < j; ++q) {
        if (p != q) neighbour_pairs.emplace_back(edges[p].triangle, edges[q].triangle);
      }
    }
    i = j;
  }
  surface_neighbours_ = rowsFromPairs(surfaceTriangleCount(), std::move(neighbour_pairs));

  for (const Triangle& tri : surface_triangles_) {
    surface_nodes_.insert(surface_nodes_.end(), tri.begin(), tri.end());
  }
  std::sort(surface_nodes_.begin(), surface_nodes_.end());
  surface_nodes_.erase(std::unique(surface_nodes_.begin(), surface_nodes_.end()),
                       surface_nodes_.end());

  std::vector<std::pair<int, int>> incidence;
  incidence.reserve(tets_.size() * 4);
  for (int t = 0; t < tetCount(); ++t) {
    for (int n : tets_[static_cast<size_t>(t)]) {
      assert(n >= 0 && n < node_count);
      incidence.emplace_back(n, t);
    }
  }
  node_tets_ = rowsFromPairs(node_count, std::move(incidence));
}

double TetMesh::restVolume(int t) const {
  const Tet& tet = tets_[static_cast<size_t>(t)];
  const auto& x = rest_positions_;
  return sixSignedVolume(x[static_cast<size_t>(tet[0])], x[static_cast<size_t>(tet[1])],
                         x[static_cast<size_t>(tet[2])], x[static_cast<size_t>(tet[3])]) /
         6.0;
}

double TetMesh::totalRestVolume() const {
  double sum = 0;
  for (int t = 0; t < tetCount(); ++t)
    sum += restVolume(t);
  return sum;
}

Eigen::Vector3d TetMesh::boundsMin() const {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const auto& p : rest_positions_)
    lo = lo.cwiseMin(p);
  return lo;
}

Eigen::Vector3d TetMesh::boundsMax() const {
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  for (const auto& p : rest_positions_)
    hi = hi.cwiseMax(p);
  return hi;
}

}  // namespace torsion
