#include "torsion/contact/node_anchors.h"

#include "torsion/bt_conversions.h"
#include "torsion/contact/rigid_contact.h"

namespace torsion {

int NodeAnchors::add(const btCollisionObject* object, std::vector<int> nodes,
                     const FemState& state) {
  const int id = static_cast<int>(anchors_.size());
  NodeAnchor anchor;
  anchor.object = object;
  const btTransform to_local = object->getWorldTransform().inverse();
  for (int node : nodes) {
    if (node_anchor_.size() <= static_cast<size_t>(node))
      node_anchor_.resize(static_cast<size_t>(node) + 1, -1);
    node_anchor_[static_cast<size_t>(node)] = id;
    anchor.local_points.push_back(toEigen(to_local * toBt(state.position(node))));
    ++anchored_count_;
  }
  anchor.nodes = std::move(nodes);
  anchors_.push_back(std::move(anchor));
  return id;
}

void NodeAnchors::remove(int anchor) {
  NodeAnchor& a = anchors_[static_cast<size_t>(anchor)];
  for (int node : a.nodes) {
    node_anchor_[static_cast<size_t>(node)] = -1;
    --anchored_count_;
  }
  a = NodeAnchor{};
}

// ---- the anchors' part of RigidContactSolver ----------------------------------------------

void RigidContactSolver::recordAnchorStartPoses() {
  // Stage 1: a multibody link is still at its start pose (Bullet moves it in stage 3).
  for (const NodeAnchor& anchor : anchors_.anchors()) {
    if (anchor.object != nullptr) links_.recordStartPose(anchor.object);
  }
}

void RigidContactSolver::addAnchorContacts(const FemState& state,
                                           const NodeConstraints& constraints) {
  for (const NodeAnchor& anchor : anchors_.anchors()) {
    if (anchor.object == nullptr) continue;
    const btTransform pose = startPoseOf(*anchor.object);
    const int partner = partnerIndex(anchor.object);
    const Eigen::Vector3d com = partners_[static_cast<size_t>(partner)].com;
    for (size_t a = 0; a < anchor.nodes.size(); ++a) {
      const int node = anchor.nodes[a];
      // A node a hand or node group holds follows its script, not the anchor.
      if (constraints.kind(node) == NodeConstraints::Kind::kFull) continue;
      const Eigen::Vector3d target = toEigen(pose * toBt(anchor.local_points[a]));
      const Eigen::Vector3d drift = target - state.position(node);
      NodeContact c;
      c.node = node;
      c.partner = partner;
      c.anchored = true;
      c.state = NodeContact::State::kStick;
      // The sticking constraint closes the gap along its normal: here the whole drift.
      const double distance = drift.norm();
      c.normal = distance > 0 ? Eigen::Vector3d(drift / distance) : Eigen::Vector3d::UnitZ();
      c.gap = -distance;
      c.distance = -distance;  // (no shape: the drift is the only distance)
      c.lever = target - com;
      int& slot = node_contact_[static_cast<size_t>(node)];
      if (slot >= 0) {
        contacts_[static_cast<size_t>(slot)] = c;
      } else {
        slot = static_cast<int>(contacts_.size());
        contacts_.push_back(c);
      }
    }
  }
}

}  // namespace torsion
