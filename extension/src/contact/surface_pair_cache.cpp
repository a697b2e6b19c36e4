#include "torsion/contact/surface_pair_cache.h"

#include <algorithm>

namespace torsion {

namespace {

// Surface nodes (edges) per block of the parallel build: fixed, whatever the thread count.
constexpr int kBuildBlock = 64;
// The lists are built over a skin this much wider than the one they are kept for: the tree's
// boxes are rounded outwards (to float on float Bullet), and a pair's boxes a rounding apart
// must still be listed.
constexpr double kBuildSkinFactor = 1.01;

// The box over an edge's two corners at the start and at the end of the motion.
void sweptEdgeBox(const std::array<int, 2>& e, const Eigen::VectorXd& start,
                  const Eigen::VectorXd& end, Eigen::Vector3d& lo, Eigen::Vector3d& hi) {
  const Eigen::Vector3d p0 = start.segment<3>(3 * e[0]), q0 = start.segment<3>(3 * e[1]);
  const Eigen::Vector3d p1 = end.segment<3>(3 * e[0]), q1 = end.segment<3>(3 * e[1]);
  lo = p0.cwiseMin(q0).cwiseMin(p1).cwiseMin(q1);
  hi = p0.cwiseMax(q0).cwiseMax(p1).cwiseMax(q1);
}

}  // namespace

SurfacePairCache::SurfacePairCache(std::vector<Triangle> triangles, const SurfaceEdges& edges,
                                   std::vector<int> surface_nodes)
    : tree_(std::move(triangles)), edges_(edges), surface_nodes_(std::move(surface_nodes)) {}

bool SurfacePairCache::prepare(const Eigen::VectorXd& start, const Eigen::VectorXd& end,
                               double margin, double skin, const Parallel& parallel) {
  if (!(skin > 0)) {
    skin_ = 0;
    tree_.refit(start, end, margin);
    ++builds_;
    return true;
  }
  const bool rebuild = skin != skin_ || margin != margin_ || !withinSkin(start, end);
  if (rebuild) {
    skin_ = skin;
    margin_ = margin;
    build(start, end, margin, parallel);
  }
  tree_.setBoxes(start, end, margin);  // what a fresh search's refit would give
  return rebuild;
}

bool SurfacePairCache::withinSkin(const Eigen::VectorXd& start, const Eigen::VectorXd& end) const {
  for (size_t k = 0; k < surface_nodes_.size(); ++k) {
    const int p = surface_nodes_[k];
    const Eigen::Vector3d x = start.segment<3>(3 * p), e = end.segment<3>(3 * p);
    if (((x.cwiseMin(e) - built_lo_[k]).array() < -skin_).any() ||
        ((x.cwiseMax(e) - built_hi_[k]).array() > skin_).any())
      return false;
  }
  return true;
}

void SurfacePairCache::build(const Eigen::VectorXd& start, const Eigen::VectorXd& end,
                             double margin, const Parallel& parallel) {
  ++builds_;
  // A pair that overlaps later, each box at most skin_ beyond its box now, overlaps now with
  // both boxes grown by skin_: the tree's by margin + skin, the query's by skin.
  const double grow = kBuildSkinFactor * skin_;
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(grow);
  tree_.refit(start, end, margin + grow);
  built_lo_.resize(surface_nodes_.size());
  built_hi_.resize(surface_nodes_.size());
  node_triangles_.resize(surface_nodes_.size());
  const int node_blocks = (static_cast<int>(surface_nodes_.size()) + kBuildBlock - 1) / kBuildBlock;
  parallel.forRange(node_blocks, 1, [&](int first, int last) {
    for (size_t k = static_cast<size_t>(first) * kBuildBlock;
         k < std::min(surface_nodes_.size(), static_cast<size_t>(last) * kBuildBlock); ++k) {
      const int p = surface_nodes_[k];
      const Eigen::Vector3d x = start.segment<3>(3 * p), e = end.segment<3>(3 * p);
      built_lo_[k] = x.cwiseMin(e);
      built_hi_[k] = x.cwiseMax(e);
      tree_.query(built_lo_[k] - pad, built_hi_[k] + pad, node_triangles_[k]);
    }
  });
  // Edges: the later edges of the triangles found, not sharing a node, whose own boxes come
  // within the margin (each box grown by the skin): the solver's cheap box test, widened.
  const std::vector<std::array<int, 2>>& edges = edges_.edges;
  std::vector<Eigen::Vector3d> lo(edges.size()), hi(edges.size());
  for (size_t i = 0; i < edges.size(); ++i)
    sweptEdgeBox(edges[i], start, end, lo[i], hi[i]);
  later_edges_.resize(edges.size());
  const int edge_blocks = (static_cast<int>(edges.size()) + kBuildBlock - 1) / kBuildBlock;
  const double reach = margin + 2 * grow;
  parallel.forRange(edge_blocks, 1, [&](int first, int last) {
    std::vector<int> triangles;
    for (int i = first * kBuildBlock;
         i < std::min(static_cast<int>(edges.size()), last * kBuildBlock); ++i) {
      const size_t si = static_cast<size_t>(i);
      const std::array<int, 2>& e = edges[si];
      tree_.query(lo[si] - pad, hi[si] + pad, triangles);
      std::vector<int>& later = later_edges_[si];
      later.clear();
      for (int t : triangles) {
        for (int j : edges_.triangle_edges[static_cast<size_t>(t)]) {
          if (j <= i) continue;
          const std::array<int, 2>& f = edges[static_cast<size_t>(j)];
          if (f[0] == e[0] || f[0] == e[1] || f[1] == e[0] || f[1] == e[1]) continue;
          const size_t sj = static_cast<size_t>(j);
          if (((lo[sj].array() - reach) > hi[si].array()).any() ||
              ((hi[sj].array() + reach) < lo[si].array()).any())
            continue;
          later.push_back(j);
        }
      }
      std::sort(later.begin(), later.end());
      later.erase(std::unique(later.begin(), later.end()), later.end());
    }
  });
}

void SurfacePairCache::nodeTriangles(int k, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                     std::vector<int>& out) const {
  if (!cached()) {
    tree_.query(lo, hi, out);
    return;
  }
  out.clear();
  const btDbvtVolume box = SurfaceTree::queryBox(lo, hi);
  for (int t : node_triangles_[static_cast<size_t>(k)])
    if (tree_.overlaps(t, box)) out.push_back(t);
}

const std::vector<int>& SurfacePairCache::laterEdges(int i, const Eigen::Vector3d& lo,
                                                     const Eigen::Vector3d& hi,
                                                     std::vector<int>& scratch,
                                                     std::vector<int>& out) const {
  // Kept: the list as built. An edge j whose box over the motion comes within the margin of
  // edge i's overlaps it with the margin, and so does the box of each triangle on j (which
  // contains j's box, grown by the margin, rounded outwards): the tree walk would have found it.
  // The others on the list are for the caller's box test to drop.
  if (cached()) return later_edges_[static_cast<size_t>(i)];
  out.clear();
  tree_.query(lo, hi, scratch);
  out.reserve(3 * scratch.size());
  for (int t : scratch)
    for (int j : edges_.triangle_edges[static_cast<size_t>(t)])
      if (j > i) out.push_back(j);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace torsion
