#include "torsion/contact/surface_contact_set.h"

#include <algorithm>
#include <cmath>

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

void SurfaceContactSet::setPenalties(const std::vector<Eigen::Matrix3d>& diagonal_blocks,
                                     double penalty_factor) {
  for (SurfaceContact& c : contacts_) {
    double inverse_mass = 0;
    for (size_t k = 0; k < 4; ++k) {
      const double m = c.normal.dot(diagonal_blocks[static_cast<size_t>(c.nodes[k])] * c.normal);
      inverse_mass += c.beta[k] * c.beta[k] / m;
    }
    c.penalty = penalty_factor / inverse_mass;
  }
}

Eigen::Vector3d SurfaceContactSet::relativeVelocity(const SurfaceContact& c,
                                                    const Eigen::VectorXd& v) const {
  Eigen::Vector3d u = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < 4; ++k)
    u += c.beta[k] * v.segment<3>(3 * c.nodes[k]);
  return u;
}

void SurfaceContactSet::addRightHandSide(double dt, Eigen::VectorXd& b) const {
  for (const SurfaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const Eigen::Vector3d r = c.multiplier - c.penalty * c.normal * (c.gap / dt);
    for (size_t k = 0; k < 4; ++k)
      b.segment<3>(3 * c.nodes[k]) += c.beta[k] * r;
  }
}

void SurfaceContactSet::addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  for (const SurfaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const Eigen::Vector3d u = relativeVelocity(c, y);
    const Eigen::Vector3d f = c.state == SurfaceContact::State::kStick
                                  ? Eigen::Vector3d(c.penalty * u)
                                  : Eigen::Vector3d(c.penalty * c.normal * c.normal.dot(u));
    for (size_t k = 0; k < 4; ++k)
      out.segment<3>(3 * c.nodes[k]) += c.beta[k] * f;
  }
}

void SurfaceContactSet::addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const {
  for (const SurfaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const Eigen::Matrix3d p = c.state == SurfaceContact::State::kStick
                                  ? Eigen::Matrix3d::Identity()
                                  : Eigen::Matrix3d(c.normal * c.normal.transpose());
    for (size_t k = 0; k < 4; ++k)
      blocks[static_cast<size_t>(c.nodes[k])] += c.penalty * c.beta[k] * c.beta[k] * p;
  }
}

bool SurfaceContactSet::update(const Eigen::VectorXd& v, double dt, double activation_tolerance,
                               double gap_tolerance) {
  bool converged = true;
  for (SurfaceContact& c : contacts_) {
    if (c.determined) continue;
    const Eigen::Vector3d h = relativeVelocity(c, v) + c.normal * (c.gap / dt);
    const double hn = c.normal.dot(h);
    c.end_gap = dt * hn;
    if (c.state == SurfaceContact::State::kInactive) {
      // A released contact comes back only if it penetrates beyond the tolerance (anti-cycling).
      const double threshold = c.releases > 0 ? gap_tolerance : activation_tolerance;
      if (c.end_gap >= -threshold) {
        if (c.end_gap < -gap_tolerance) converged = false;
        continue;
      }
    }
    const SurfaceContact::State old_state = c.state;
    const Eigen::Vector3d old_multiplier = c.multiplier;
    const Eigen::Vector3d trial = c.multiplier - c.penalty * h;
    const double ln = c.normal.dot(trial);
    if (ln <= 0) {
      if (c.state != SurfaceContact::State::kInactive) {
        ++c.releases;
        converged = false;
      }
      c.state = SurfaceContact::State::kInactive;
      c.multiplier.setZero();
      continue;
    }
    const Eigen::Vector3d tangential = trial - c.normal * ln;
    const double bound = c.friction * ln;
    const bool may_stick = old_state != SurfaceContact::State::kSlide || c.switches < 2;
    if (c.friction > 0 && tangential.norm() <= bound && may_stick) {
      c.state = SurfaceContact::State::kStick;
      c.multiplier = trial;
    } else {
      // Sliding: Coulomb's friction opposes the slip, under-relaxed half way from the last value:
      // taken from the trial alone, the friction and the slip it causes alternated between two
      // states.
      c.state = SurfaceContact::State::kSlide;
      const Eigen::Vector3d slip = h - c.normal * hn;
      const Eigen::Vector3d direction = slip.norm() > 0 ? Eigen::Vector3d(-slip.normalized())
                                                        : Eigen::Vector3d(tangential.normalized());
      Eigen::Vector3d friction = bound * direction;
      if (old_state == SurfaceContact::State::kSlide) {
        const Eigen::Vector3d old_t = old_multiplier - c.normal * c.normal.dot(old_multiplier);
        friction = 0.5 * (friction + old_t);
        if (friction.norm() > bound) friction *= bound / friction.norm();
      }
      if (!friction.allFinite()) friction.setZero();
      c.multiplier = c.normal * ln + friction;
    }
    if (old_state != SurfaceContact::State::kInactive && c.state != old_state) ++c.switches;
    if (c.state != old_state || std::abs(c.end_gap) > gap_tolerance) converged = false;
    const Eigen::Vector3d slip = h - c.normal * hn;
    if (c.state == SurfaceContact::State::kStick && dt * slip.norm() > gap_tolerance)
      converged = false;
    // Sliding friction follows the normal impulse: settled once it moves by less than 1 %.
    if (c.state == SurfaceContact::State::kSlide) {
      const Eigen::Vector3d change = c.multiplier - old_multiplier;
      if ((change - c.normal * c.normal.dot(change)).norm() > 2e-2 * bound) converged = false;
    }
  }
  return converged;
}

double SurfaceContactSet::maxGapError() const {
  double worst = 0;
  for (const SurfaceContact& c : contacts_) {
    if (c.determined) continue;
    worst = std::max(
        worst, c.state == SurfaceContact::State::kInactive ? -c.end_gap : std::abs(c.end_gap));
  }
  return worst;
}

double SurfaceContactSet::maxEndPenetration() const {
  double deepest = 0;
  for (const SurfaceContact& c : contacts_)
    if (!c.determined) deepest = std::max(deepest, -c.end_gap);
  return deepest;
}

}  // namespace torsion
