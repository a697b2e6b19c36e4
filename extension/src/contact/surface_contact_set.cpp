#include "torsion/contact/surface_contact_set.h"

#include <algorithm>
#include <cmath>

namespace torsion {

namespace {

// Stick/slide switches of one contact per step before it keeps its state (anti-cycling).
constexpr int kMaxSwitches = 4;

Eigen::Matrix3d contactBlock(const SurfaceContact& c) {
  return SurfaceContactSet::operatorBlock(c);
}

}  // namespace

Eigen::Matrix3d SurfaceContactSet::operatorBlock(const SurfaceContact& c) {
  if (c.state == SurfaceContact::State::kStick) return c.penalty * Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d nn = c.normal * c.normal.transpose();
  return c.penalty * nn + c.tangential_stiffness * (Eigen::Matrix3d::Identity() - nn);
}

Eigen::Vector3d SurfaceContactSet::rightHandSideImpulse(const SurfaceContact& c, double dt) {
  const Eigen::Vector3d lambda = c.state == SurfaceContact::State::kStick
                                     ? c.multiplier
                                     : Eigen::Vector3d(c.normal * c.normal.dot(c.multiplier));
  return lambda - c.penalty * c.normal * ((c.gap - c.target_gap) / dt);
}

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
      // Sliding: its first solve holds it at the penalty; the slip it then shows sets k_t.
      if (contact.friction > 0) contact.tangential_stiffness = -1;
    }
  }
  contacts_.push_back(contact);
}

void SurfaceContactSet::setPenalties(const std::vector<Eigen::Matrix3d>& diagonal_blocks,
                                     double penalty_factor) {
  penalty_factor_ = penalty_factor;
  for (SurfaceContact& c : contacts_) {
    double inverse_mass = 0;
    for (size_t k = 0; k < 4; ++k) {
      const double m = c.normal.dot(diagonal_blocks[static_cast<size_t>(c.nodes[k])] * c.normal);
      inverse_mass += c.beta[k] * c.beta[k] / m;
    }
    c.penalty = penalty_factor / inverse_mass;
    if (c.tangential_stiffness < 0) c.tangential_stiffness = c.penalty;
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
    const Eigen::Vector3d r = rightHandSideImpulse(c, dt);
    for (size_t k = 0; k < 4; ++k)
      b.segment<3>(3 * c.nodes[k]) += c.beta[k] * r;
  }
}

void SurfaceContactSet::addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  for (const SurfaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const Eigen::Vector3d f = contactBlock(c) * relativeVelocity(c, y);
    for (size_t k = 0; k < 4; ++k)
      out.segment<3>(3 * c.nodes[k]) += c.beta[k] * f;
  }
}

void SurfaceContactSet::addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const {
  for (const SurfaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const Eigen::Matrix3d p = contactBlock(c);
    for (size_t k = 0; k < 4; ++k)
      blocks[static_cast<size_t>(c.nodes[k])] += c.beta[k] * c.beta[k] * p;
  }
}

bool SurfaceContactSet::beyondTolerance(const SurfaceContact& c, double impulse, double dt,
                                        double gap_tolerance) const {
  // The contact's effective mass is its penalty over penalty_factor (setPenalties).
  return dt * impulse * penalty_factor_ > gap_tolerance * c.penalty;
}

bool SurfaceContactSet::update(const Eigen::VectorXd& v, double dt, double activation_tolerance,
                               double gap_tolerance) {
  using State = SurfaceContact::State;
  bool converged = true;
  for (SurfaceContact& c : contacts_) {
    if (c.determined) continue;
    const Eigen::Vector3d u = relativeVelocity(c, v);
    const double un = c.normal.dot(u);
    const double hn = un + (c.gap - c.target_gap) / dt;  // towards the target gap
    c.end_gap = dt * hn;
    if (c.state == State::kInactive) {
      // A released contact comes back only if it penetrates beyond the tolerance (anti-cycling).
      const double threshold = c.releases > 0 ? gap_tolerance : activation_tolerance;
      if (c.end_gap >= -threshold) {
        if (c.end_gap < -gap_tolerance) converged = false;
        continue;
      }
    }
    const State old_state = c.state;
    const double old_stiffness = c.tangential_stiffness;
    const double ln = c.normal.dot(c.multiplier) - c.penalty * hn;
    if (ln <= 0) {
      if (c.state != State::kInactive) {
        ++c.releases;
        // The solve pulled with -ln: within the tolerance when that moved it less than it.
        if (!within_tolerance_ || beyondTolerance(c, -ln, dt, gap_tolerance)) converged = false;
      }
      c.state = State::kInactive;
      c.multiplier.setZero();
      c.tangential_stiffness = 0;
      continue;
    }
    const Eigen::Vector3d slip = u - c.normal * un;  // tangential relative velocity
    const double speed = slip.norm();
    const double bound = c.friction * ln;
    const bool may_switch = c.switches < kMaxSwitches;
    double outside_cone = 0;  // N s, the part of the solve's friction impulse beyond Coulomb's
    // k_t Coulomb's friction asks for at this slip, at most the penalty (then it sticks).
    const double wanted = speed * c.penalty <= bound ? c.penalty : bound / speed;
    if (c.friction <= 0) {
      c.state = State::kSlide;
      c.tangential_stiffness = 0;
      c.multiplier = c.normal * ln;
    } else if (old_state == State::kStick) {
      Eigen::Vector3d trial =
          c.multiplier - c.normal * c.normal.dot(c.multiplier) - c.penalty * slip;
      if (trial.norm() <= bound || !may_switch) {
        if (trial.norm() > bound) trial *= bound / trial.norm();
        c.multiplier = c.normal * ln + trial;
      } else {
        outside_cone = trial.norm() - bound;
        c.state = State::kSlide;
        c.tangential_stiffness = wanted;
        c.multiplier = c.normal * ln - wanted * slip;
      }
    } else if (wanted >= c.penalty && (may_switch || old_state == State::kInactive)) {
      // Slower than mu lambda_n / rho: sticks, from the friction impulse of this solve.
      c.state = State::kStick;
      const double used = old_state == State::kSlide ? std::max(0.0, old_stiffness) : 0.0;
      c.multiplier = c.normal * ln - used * slip;
    } else {
      c.state = State::kSlide;
      // Still sliding: Kacanov's k_t may swing about its fixed point (the slip's speed falls as
      // k_t rises); relaxed, it settles (friction_relaxation_, setFrictionRelaxation).
      const double relaxed =
          old_state == State::kSlide && old_stiffness > 0
              ? friction_relaxation_ * wanted + (1 - friction_relaxation_) * old_stiffness
              : wanted;
      c.tangential_stiffness = relaxed;
      c.multiplier = c.normal * ln - relaxed * slip;
    }
    if (!c.multiplier.allFinite()) c.multiplier = c.normal * ln;
    if (old_state != State::kInactive && c.state != old_state) ++c.switches;
    // Judged within the tolerance, a switch counts through the impulse it corrects and an
    // activation through its end gap.
    if (within_tolerance_ ? beyondTolerance(c, outside_cone, dt, gap_tolerance)
                          : c.state != old_state)
      converged = false;
    if (std::abs(c.end_gap) > gap_tolerance) converged = false;
    if (c.state == State::kStick && dt * speed > gap_tolerance) converged = false;
    // Sliding friction settled: its impulse moved by less than 2 % of mu lambda_n (or, judged
    // within the tolerance, by less than moves the contact by it).
    if (c.state == State::kSlide && c.friction > 0) {
      const double moved = std::abs(c.tangential_stiffness - old_stiffness) * speed;
      if (moved > 2e-2 * bound &&
          !(within_tolerance_ && !beyondTolerance(c, moved, dt, gap_tolerance)))
        converged = false;
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
    if (!c.determined) deepest = std::max(deepest, -(c.end_gap + c.target_gap));
  return deepest;
}

}  // namespace torsion
