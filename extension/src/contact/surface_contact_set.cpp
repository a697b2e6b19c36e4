#include "torsion/contact/surface_contact_set.h"

#include <algorithm>

namespace torsion {

SurfaceContactSet::WarmStarts SurfaceContactSet::warmStarts() const {
  WarmStarts warm;
  for (const SurfaceContact& c : contacts_) {
    if (c.state != SurfaceContact::State::kInactive && !c.determined)
      warm.emplace_back(key(c), c.multiplier);
  }
  std::sort(warm.begin(), warm.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  return warm;
}

void SurfaceContactSet::save(CheckpointWriter& out) const {
  // After setWarmStarts and before a step, warm_ is what the next step takes (contacts_ is empty).
  const WarmStarts warm = restored_ ? warm_ : warmStarts();
  out.u32(warm.size());
  for (const auto& [k, lambda] : warm) {
    out.raw(k);
    out.vec3(lambda);
  }
}

Status SurfaceContactSet::restore(CheckpointReader& in) {
  WarmStarts warm(in.count(8 + 3 * 8));
  for (auto& [k, lambda] : warm) {
    k = in.raw<std::uint64_t>();
    lambda = in.vec3();
  }
  // warmStartOf searches them by key.
  for (size_t i = 0; i < warm.size() && in.ok(); ++i) {
    if (!warm[i].second.allFinite() || (i > 0 && warm[i - 1].first > warm[i].first))
      in.refuse("contact multipliers out of key order or not finite");
  }
  if (!in.ok()) return in.error();
  setWarmStarts(std::move(warm));
  return Ok{};
}

void SurfaceContactSet::beginStep() {
  // The multipliers the last step ended with become this step's warm starts.
  if (!restored_) warm_ = warmStarts();
  restored_ = false;
  contacts_.clear();
}

const Eigen::Vector3d* SurfaceContactSet::warmStartOf(std::uint64_t k) const {
  const auto it =
      std::lower_bound(warm_.begin(), warm_.end(), k,
                       [](const auto& entry, std::uint64_t x) { return entry.first < x; });
  return it != warm_.end() && it->first == k ? &it->second : nullptr;
}

void SurfaceContactSet::add(SurfaceContact contact) {
  const std::uint64_t k = key(contact);
  const auto it =
      std::lower_bound(warm_.begin(), warm_.end(), k,
                       [](const auto& entry, std::uint64_t x) { return entry.first < x; });
  contact.state = SurfaceContact::State::kInactive;
  contact.multiplier.setZero();
  if (it != warm_.end() && it->first == k) {
    // A resting contact starts where the last step left it (rotated into this step's normal).
    const double ln = std::max(0.0, contact.normal.dot(it->second));
    if (ln > 0) {
      const Eigen::Vector3d tangential =
          it->second - contact.normal * contact.normal.dot(it->second);
      const double bound = contact.friction * ln;
      contact.multiplier =
          contact.normal * ln + (tangential.norm() <= bound
                                     ? tangential
                                     : Eigen::Vector3d(tangential.normalized() * bound));
      contact.state = contact.friction > 0 && tangential.norm() < bound
                          ? SurfaceContact::State::kStick
                          : SurfaceContact::State::kSlide;
    }
  }
  contacts_.push_back(contact);
}

double SurfaceContactSet::maxEndPenetration() const {
  double deepest = 0;
  for (const SurfaceContact& c : contacts_)
    if (!c.determined) deepest = std::max(deepest, -(c.end_gap + c.target_gap));
  return deepest;
}

}  // namespace torsion
