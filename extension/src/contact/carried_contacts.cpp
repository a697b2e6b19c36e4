// The warm starts of RigidContactSolver in a form that names the rigid objects alone, for
// checkpoints that leave memory. Mirrors what detect() and the island's rows read from the last
// step: active, non-held node contacts with their partner's object, and the face rows' features.

#include "torsion/contact/rigid_contact.h"

namespace torsion {

CarriedContacts RigidContactSolver::carriedContacts() const {
  CarriedContacts carried;
  for (const NodeContact& c : contacts_) {
    if (c.state == NodeContact::State::kInactive || c.held) continue;
    carried.nodes.push_back(
        {c.node, partners_[static_cast<size_t>(c.partner)].object, c.state, c.impulse, c.normal});
  }
  carried.features = lagged_features_;
  return carried;
}

void RigidContactSolver::restoreCarriedContacts(const CarriedContacts& carried) {
  // Partners here only name the objects: detect() rebuilds them from this step's candidates.
  auto partner = [this](const btCollisionObject* object) {
    for (size_t k = 0; k < partners_.size(); ++k) {
      if (partners_[k].object == object) return static_cast<int>(k);
    }
    RigidPartner p;
    p.object = object;
    partners_.push_back(p);
    return static_cast<int>(partners_.size()) - 1;
  };
  partners_.clear();
  contacts_.clear();
  std::fill(node_contact_.begin(), node_contact_.end(), -1);
  for (const CarriedContacts::Node& n : carried.nodes) {
    NodeContact c;
    c.normal = n.normal;
    c.lever.setZero();
    c.node = n.node;
    c.partner = partner(n.object);
    c.state = n.state;
    c.impulse = n.impulse;
    contacts_.push_back(c);
  }
  lagged_features_ = carried.features;
}

}  // namespace torsion
