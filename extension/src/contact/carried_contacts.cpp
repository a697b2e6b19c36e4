// The warm starts of RigidContactSolver in a form that names the rigid objects alone, for
// checkpoints. Mirrors what detect() and the island's rows read from the last step: active,
// non-held node contacts with their partner's object, and the face rows' features.

#include <cmath>

#include "torsion/contact/rigid_contact.h"
#include "torsion/format_number.h"

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

namespace {

// Bytes per record, the least a count of them can take (CheckpointReader::count).
constexpr size_t kNodeBytes = 4 + 4 + 1 + 6 * 8;
constexpr size_t kFeatureBytes = 4 + 4 * 8;

void readNode(CheckpointReader& in, int node_count, CarriedContacts::Node& n) {
  n.node = in.i32();
  n.object = in.object();
  n.state = in.enumeration(NodeContact::State::kStick);
  n.impulse = in.vec3();
  n.normal = in.vec3();
  if (!in.ok()) return;
  if (n.node < 0 || n.node >= node_count) {
    in.refuse("a contact of node " + std::to_string(n.node) + " (the body has " +
              std::to_string(node_count) + " nodes)");
  } else if (!n.impulse.allFinite() || !n.normal.allFinite()) {
    in.refuse("a node contact's impulse or normal that is not finite");
  }
}

void readFeature(CheckpointReader& in, CarriedContacts::Feature& f) {
  f.object = in.object();
  f.lever = in.vec3();
  f.normal_impulse = in.f64();
  if (in.ok() && !(f.lever.allFinite() && std::isfinite(f.normal_impulse)))
    in.refuse("a face row's lever or normal impulse that is not finite");
}

}  // namespace

void RigidContactSolver::save(CheckpointWriter& out) const {
  out.f64(settings_.friction);
  const CarriedContacts carried = carriedContacts();
  out.u32(carried.nodes.size());
  for (const CarriedContacts::Node& n : carried.nodes) {
    out.i32(n.node);
    out.object(n.object);
    out.u8(static_cast<int>(n.state));
    out.vec3(n.impulse);
    out.vec3(n.normal);
  }
  out.u32(carried.features.size());
  for (const CarriedContacts::Feature& f : carried.features) {
    out.object(f.object);
    out.vec3(f.lever);
    out.f64(f.normal_impulse);
  }
}

Status RigidContactSolver::restore(CheckpointReader& in) {
  const double friction = in.f64();
  if (in.ok() && !(std::isfinite(friction) && friction >= 0))
    in.refuse("a contact friction of " + formatNumber(friction));
  CarriedContacts carried;
  carried.nodes.resize(in.count(kNodeBytes));
  for (CarriedContacts::Node& n : carried.nodes)
    readNode(in, model_->nodeCount(), n);
  carried.features.resize(in.count(kFeatureBytes));
  for (CarriedContacts::Feature& f : carried.features)
    readFeature(in, f);
  if (!in.ok()) return in.error();
  settings_.friction = friction;
  restoreCarriedContacts(carried);
  return Ok{};
}

}  // namespace torsion
