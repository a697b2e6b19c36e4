#pragma once
// Whether one of Bullet's soft bodies (cloth, rope, btSoftBodyHelpers volume) touches an FEM body
// in a substep: FemSoftBodySolver reports such pairs (UnsupportedContact), since they would pass
// through each other. Comparing the two bodies' nodes alone misses a cloth node that lands on the
// middle of a coarse FEM face, far from every FEM node, so the pair touches when
//  - a node of the Bullet body comes within both margins of the FEM body's surface triangles, its
//    motion over the substep (m_q to m_x) crosses one of them, or it ends inside the FEM body's
//    closed surface;
//  - a surface node of the FEM body comes within both margins of one of the Bullet body's faces
//    (when it has faces) or its motion crosses one.
// Its own file: geometry the solver's seam with Bullet need not carry. Each body's triangle tree
// (contact/surface_tree.h) is built once and refit at most once a substep, on first use; only
// nodes inside the other body's box are queried.

#include <BulletSoftBody/btSoftBody.h>

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <memory>
#include <vector>

#include "torsion/contact/surface_tree.h"

namespace torsion {

class FemBody;

class SoftBodyTouch {
 public:
  SoftBodyTouch();
  ~SoftBodyTouch();
  SoftBodyTouch(const SoftBodyTouch&) = delete;
  SoftBodyTouch& operator=(const SoftBodyTouch&) = delete;

  /// A new substep (predictMotion): the bodies' trees are refit on their next use.
  void beginSubstep() { ++round_; }
  /// Whether `soft` (one of Bullet's soft bodies) and `fem` touch in this substep, read from both
  /// btSoftBody's nodes after the substep's prediction (m_q: start, m_x: end).
  bool touches(FemBody& fem, btSoftBody& soft);
  /// Drops what is kept for an FEM body (removed from the world).
  void forget(const FemBody* fem);
  /// Drops what is kept for Bullet's soft bodies no longer in the world.
  void keepOnly(const btAlignedObjectArray<btSoftBody*>& bullet_bodies);

  /// A body's surface over the substep: triangles in a tree over their swept boxes, nodes at the
  /// start and end.
  struct Swept {
    std::vector<int> nodes;  // the nodes tested against the other body's triangles
    std::unique_ptr<SurfaceTree> tree;
    Eigen::VectorXd start, end;  // 3n
    Eigen::Vector3d lo, hi;      // box of every node over the substep
    double margin = 0;
    std::uint64_t round = 0;  // the substep it was refit for
  };

 private:
  Swept& sweptFem(FemBody& fem);
  Swept& sweptSoft(btSoftBody& soft);

  std::map<const FemBody*, std::unique_ptr<Swept>> fem_;
  std::map<const btSoftBody*, std::unique_ptr<Swept>> soft_;
  std::uint64_t round_ = 1;
  std::vector<int> candidates_;  // the tree queries' answers, reused from pair to pair
};

}  // namespace torsion
