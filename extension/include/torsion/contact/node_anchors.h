#pragma once
// Two-way anchors (docs/contact.md, "Anchors"): FEM nodes glued to a rigid body or a multibody
// link. Each anchored node keeps the offset it had in the body's frame when it was anchored. In
// the step's contact solve an anchored node is a contact that sticks for good: its velocity is the
// body's at that point plus the drift correction (target - x) / dt, with the body's 6 velocities
// among the CG unknowns when it is dynamic. The pull is therefore implicit and momentum-exact (to
// the CG's tolerance) whatever the mass ratio, and an anchor to a kinematic or static body is a
// prescription that follows it exactly. Touched only by the simulation thread.

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>

#include <Eigen/Core>
#include <vector>

#include "torsion/solve/fem_state.h"

namespace torsion {

struct NodeAnchor {
  const btCollisionObject* object = nullptr;  ///< null once removed
  std::vector<int> nodes;
  std::vector<Eigen::Vector3d> local_points;  ///< m, each node in the object's frame
};

class NodeAnchors {
 public:
  /// Anchors `nodes` at their positions in `state` to `object` at its current pose. Returns the
  /// anchor's id. Nodes must be valid and not anchored already (FemBody::anchorNodes checks).
  int add(const btCollisionObject* object, std::vector<int> nodes, const FemState& state);
  /// Frees the anchor's nodes; its id stays reserved.
  void remove(int anchor);
  /// No anchor holds a node.
  bool empty() const { return anchored_count_ == 0; }
  /// Whether `node` is anchored (to anything).
  bool anchored(int node) const {
    return node < static_cast<int>(node_anchor_.size()) &&
           node_anchor_[static_cast<size_t>(node)] >= 0;
  }
  const std::vector<NodeAnchor>& anchors() const { return anchors_; }

 private:
  std::vector<NodeAnchor> anchors_;
  std::vector<int> node_anchor_;  // per node: anchor id or -1
  int anchored_count_ = 0;
};

}  // namespace torsion
