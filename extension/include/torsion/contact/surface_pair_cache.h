#pragma once
// The broad phase of self-contact (self_contact.h), kept across steps: which triangles a surface
// node, and which later edges a surface edge, may meet along a step's motion (docs/contact.md,
// "Self-contact", "Candidates kept across steps").
//
// A fresh search refits the surface tree (surface_tree.h) to the triangles swept over the step's
// motion, grown by the margin, and queries it with each node's (edge's) swept box. The cache
// instead keeps, per surface node and per surface edge, the pairs whose boxes came within a skin
// of each other when it was built (Verlet lists): while every surface node's swept box stays
// within `skin` of its box at the build, no pair outside the lists can overlap. Each step it
// recomputes the triangles' boxes exactly as a refit would and filters the lists by the very box
// test the tree walk makes, so it hands out the same pairs, in the same order, as a fresh search:
// the candidates, and every result after them, do not depend on the cache. A node outside its
// skin (a fast motion, a grab, a teleport, a checkpoint restored) rebuilds the lists in that
// step; the validity check looks only at positions, so nothing else has to invalidate it.
//
// skin 0 disables the cache: every step is a fresh tree search.

#include <Eigen/Core>
#include <array>
#include <vector>

#include "torsion/contact/surface_candidates.h"
#include "torsion/contact/surface_tree.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/solve/parallel.h"

namespace torsion {

class SurfacePairCache {
 public:
  /// `triangles`: the body's surface; `edges`: its surface edges (kept by reference: it must
  /// outlive the cache); `surface_nodes`: the nodes that query.
  SurfacePairCache(std::vector<Triangle> triangles, const SurfaceEdges& edges,
                   std::vector<int> surface_nodes);

  /// Prepares the queries of a search along the motion start -> end (3n positions), the
  /// triangles' boxes grown by `margin` (m): recomputes the boxes, and rebuilds the lists (on
  /// `parallel`'s threads, in fixed blocks: the same lists for any thread count) when there are
  /// none yet, the skin changed, or a surface node has left its skin (m). Returns whether it
  /// rebuilt (always, with skin 0: then every query walks the tree).
  bool prepare(const Eigen::VectorXd& start, const Eigen::VectorXd& end, double margin, double skin,
               const Parallel& parallel);

  /// The triangles whose box overlaps [lo, hi], ascending, for the k-th surface node (whose swept
  /// box [lo, hi] must be): exactly a fresh tree query's.
  void nodeTriangles(int k, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                     std::vector<int>& out) const;
  /// Edges j > i for edge i, whose swept box is [lo, hi], ascending: every edge with a triangle
  /// whose box overlaps [lo, hi] (a fresh query's edges of the triangles found), and possibly
  /// more, but only such that their own boxes over the motion do not come within `margin` of
  /// [lo, hi] (an edge with a box that close has a triangle overlapping, and is always listed),
  /// and possibly without those sharing a node with i. The caller's test of the two edges' boxes
  /// within the margin therefore leaves exactly the pairs a fresh search leaves. Returns `out`,
  /// or the kept list itself.
  const std::vector<int>& laterEdges(int i, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                     std::vector<int>& scratch, std::vector<int>& out) const;
  const std::vector<Triangle>& triangles() const { return tree_.triangles(); }
  /// Builds of the lists so far (tree walks: with skin 0, one per prepare()).
  long builds() const { return builds_; }

 private:
  bool cached() const { return skin_ > 0; }
  bool withinSkin(const Eigen::VectorXd& start, const Eigen::VectorXd& end) const;
  void build(const Eigen::VectorXd& start, const Eigen::VectorXd& end, double margin,
             const Parallel& parallel);

  SurfaceTree tree_;
  const SurfaceEdges& edges_;
  std::vector<int> surface_nodes_;
  double skin_ = -1;    // m, of the lists held (-1: none yet)
  double margin_ = -1;  // m, the margin the lists were built for
  long builds_ = 0;
  // Each surface node's swept box at the build (indexed like surface_nodes_).
  std::vector<Eigen::Vector3d> built_lo_, built_hi_;
  // The lists: triangles per surface node, later edges per edge, each ascending.
  std::vector<std::vector<int>> node_triangles_, later_edges_;
};

}  // namespace torsion
