#pragma once
// A bounding-volume tree over a body's surface triangles (Bullet's btDbvt), refitted every step
// to the triangles swept over the step's predicted motion, for node-against-triangle contact
// (self_contact.h). Leaves are created once, in triangle order, and refitted in that order, so
// the tree (and every query's order) is the same for any thread count.

#include <BulletCollision/BroadphaseCollision/btDbvt.h>

#include <Eigen/Core>
#include <vector>

#include "torsion/mesh/tet_mesh.h"

namespace torsion {

class SurfaceTree {
 public:
  explicit SurfaceTree(std::vector<Triangle> triangles);
  ~SurfaceTree();
  SurfaceTree(const SurfaceTree&) = delete;
  SurfaceTree& operator=(const SurfaceTree&) = delete;

  /// Each triangle's box covers it at `start` and at `end` (3n positions), grown by `pad` (m).
  void refit(const Eigen::VectorXd& start, const Eigen::VectorXd& end, double pad);
  /// The triangles' boxes as refit() makes them, without touching the tree: for overlaps() alone
  /// (surface_pair_cache.h), while the tree keeps the boxes of its last refit().
  void setBoxes(const Eigen::VectorXd& start, const Eigen::VectorXd& end, double pad);
  /// The box a query of [lo, hi] tests the leaves against.
  static btDbvtVolume queryBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi);
  /// Whether triangle t's box of the last setBoxes() or refit() overlaps `box` (queryBox()): the
  /// test by which query() takes a leaf, so a pair kept from an earlier query can be judged as a
  /// fresh query would judge it.
  bool overlaps(int t, const btDbvtVolume& box) const {
    return Intersect(boxes_[static_cast<size_t>(t)], box);
  }
  /// Indices of the triangles whose boxes overlap [lo, hi], ascending. Only reads the tree: any
  /// number of threads may query at once (each with its own `out`), none while refit() runs.
  void query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out) const;
  const std::vector<Triangle>& triangles() const { return triangles_; }

 private:
  std::vector<Triangle> triangles_;
  btDbvt tree_;
  std::vector<btDbvtNode*> leaves_;
  std::vector<btDbvtVolume> boxes_;  // each triangle's box, of the last setBoxes() or refit()
};

}  // namespace torsion
