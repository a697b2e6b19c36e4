// The active set of the FEM-rigid node contacts (docs/contact.md, "Active set and Coulomb
// friction"): release, activation and the stick/slide switches by Coulomb's law, with the
// anti-cycling bounds, and each rigid body's friction share.

#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/contact/rigid_contact.h"

namespace torsion {

namespace {

constexpr int kMaxSlipsPerStep = 2;
constexpr int kMaxFrictionRefinements = 8;

}  // namespace

bool RigidContactSolver::updateActiveSet(const Eigen::VectorXd& v, const Eigen::VectorXd& p,
                                         double dt) {
  bool changed = false;
  const std::vector<double>& mass = model_->nodeMasses();
  // Impulses below this are CG noise: a part in 1e4 of the largest one, or a micrometre per
  // second of the node's own momentum.
  double largest = 0;
  for (const NodeContact& c : contacts_) {
    if (!c.held && c.state != NodeContact::State::kInactive)
      largest = std::max(largest, std::abs(c.normal.dot(p.segment<3>(3 * c.node))));
  }
  // A contact on a side of the rigid body (its normal along the soft surface at the node, as a
  // box's rear face over the nodes it leaves behind) does not hold the body up: it is released
  // whenever it pulls, and not added again after its second release. Kept pulling after the one
  // release the anti-cycling allows, the rear face of a box sliding at 1.2 m/s over a stiff slab
  // pulled it back by 2.6 N s in one step. Contacts under the body keep the single release
  // (released every time, a box on a stiff slab lost its support and tipped).
  const auto sideContact = [&](const NodeContact& c) {
    const Eigen::Vector3d surface = toEigen(soft_body_->m_nodes[c.node].m_n);
    return std::abs(c.normal.dot(surface)) < 0.5 * surface.norm();
  };
  for (NodeContact& c : contacts_) {
    if (c.held || c.anchored) continue;  // an anchor sticks for good
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d vi = v.segment<3>(3 * c.node);
    const Eigen::Vector3d pi = p.segment<3>(3 * c.node);
    const double noise = std::max(1e-4 * largest, 1e-6 * mass[static_cast<size_t>(c.node)]);
    const Eigen::Vector3d rigid_v = pointVelocity(k.velocity, c.lever);
    switch (c.state) {
      case NodeContact::State::kInactive: {
        const double gap_end = c.gap + dt * c.normal.dot(vi - rigid_v);
        if (gap_end < -settings_.activation_tolerance && c.releases < 2) {
          // A node the rigid body sweeps over (held by the supporting plane, chooseSupportPlane)
          // starts sliding when it slips, and so does one that a body sliding over the surface
          // (k.sliding: all its node contacts slid last step) slips over by more than the face
          // gap tolerance; its friction follows from the next solve's normal impulse. Started
          // stuck, such a node glued a box sliding over a stiff slab for a solve (its velocity
          // fell to nothing), left Coulomb's cone, slipped, was released, came back stuck, ...
          // until its slips ran out and the step ended on the glued solve: whether that happened
          // hung on rounding, and the box's distance differed by 30 % between the two builds of
          // the system operator (docs/contact.md, "Sliding over nodes"). Other contacts start
          // stuck: a landing body's contacts slip too (its fall's speed along the surface,
          // Poisson); starting those sliding let a box keep speed the impact's friction takes
          // (16 % too far just above the friction angle), and kept a box on a tet10 slab from
          // settling; starting them sliding under a body with some contact stuck let a box
          // below the friction angle creep (7 mm in 1 s).
          // Under a sliding body, the slip with this solve's velocities or with the body's
          // velocity before the step: within a solve that other contacts glued (the loop's
          // iterate), a node the body is sliding over may seem to move with it.
          const double slipped = dt * tangentialSlip(c, vi, k.velocity).norm();
          const double slipped_under_slider =
              std::max(slipped, dt * tangentialSlip(c, vi, k.entry_velocity).norm());
          const bool slipping =
              (c.swept && slipped > settings_.activation_tolerance) ||
              (k.sliding && slipped_under_slider > std::max(settings_.activation_tolerance,
                                                            settings_.face_gap_tolerance));
          c.state =
              c.friction > 0 && !slipping ? NodeContact::State::kStick : NodeContact::State::kSlide;
          c.friction_impulse.setZero();
          changed = true;
        }
        break;
      }
      case NodeContact::State::kStick: {
        const double lambda = c.normal.dot(pi);
        const Eigen::Vector3d pt = pi - c.normal * lambda;
        if (lambda < -noise && (c.releases == 0 || sideContact(c))) {
          c.state = NodeContact::State::kInactive;
          ++c.releases;
          changed = true;
        } else if (pt.norm() > k.friction_share * c.friction * std::max(lambda, 0.0) + noise &&
                   (c.slips < kMaxSlipsPerStep || k.sliding)) {
          // Anti-cycling, as for releases: in a body pressed between two surfaces the nodes'
          // tangential and normal impulses are coupled through the body, and per-node stick/slide
          // switching can cycle. After kMaxSlipsPerStep slips in a step a contact stays stuck for
          // the rest of the step (its friction may then exceed mu lambda for that step; it is
          // re-examined from the next step on). Letting it slide instead (sticking bounded)
          // let a block below the friction angle creep 12 mm in 1 s. Under a body sliding over
          // the surface (k.sliding) there is no budget: a node stuck to a box sliding at 1.9 m/s
          // took 1.3 m/s off it in one step (a soft slab at 30 deg).
          ++c.slips;
          c.state = NodeContact::State::kSlide;
          c.friction_impulse =
              k.friction_share * c.friction * std::max(lambda, 0.0) * pt.normalized();
          changed = true;
        }
        break;
      }
      case NodeContact::State::kSlide: {
        const double lambda = c.normal.dot(pi);
        if (lambda < -noise && (c.releases == 0 || sideContact(c))) {
          c.state = NodeContact::State::kInactive;
          ++c.releases;
          c.friction_impulse.setZero();
          changed = true;
          break;
        }
        if (c.friction <= 0) break;
        Eigen::Vector3d slip = vi - rigid_v;
        slip -= c.normal * c.normal.dot(slip);
        const double speed = slip.norm();
        const double bound = k.friction_share * c.friction * std::max(c.normal.dot(pi), 0.0);
        if (speed < 1e-9 || (c.friction_impulse.norm() > 0 && slip.dot(c.friction_impulse) > 0)) {
          // The slip stopped or turned along the friction: the friction was too strong. If it
          // exceeds mu lambda of this very solve it was stale (set from an earlier, larger
          // normal impulse: pressing a soft body, its normal and tangential impulses are coupled
          // by the Poisson effect): bring it down to mu lambda and solve again. Sticking on a
          // stale friction and sliding again on the stick's tangential impulse was the cycle of
          // the kinematic press (docs/contact.md). Friction within its bound that stops the
          // slip: stick.
          const double magnitude = c.friction_impulse.norm();
          if (magnitude > bound + noise) {
            c.friction_impulse *= bound / magnitude;
            changed = true;
            break;
          }
          c.state = NodeContact::State::kStick;
          c.friction_impulse.setZero();
          changed = true;
          break;
        }
        // Under-relaxed: lambda itself depends on the friction (coupled through the body), and
        // the plain fixed point f = mu lambda(f) can oscillate; half steps converge.
        const Eigen::Vector3d target = -bound * slip / speed;
        const Eigen::Vector3d f = c.friction_impulse.norm() > 0
                                      ? Eigen::Vector3d(0.5 * (target + c.friction_impulse))
                                      : target;
        // Each refinement is a CG solve; after kMaxFrictionRefinements a slip that keeps its
        // state no longer holds the loop open (the friction still follows mu lambda).
        if ((target - c.friction_impulse).norm() > 1e-2 * (target.norm() + noise) &&
            c.friction_refinements++ < kMaxFrictionRefinements)
          changed = true;
        c.friction_impulse = f;
        break;
      }
    }
  }
  return changed;
}

void RigidContactSolver::setSlipResistances(const Eigen::VectorXd& v) {
  // As for face contacts (FaceContactSet::setSlipResistance): each solve applies a sliding node's
  // friction fixed beforehand, along the slip of the solve before, and where that slip turns
  // from solve to solve (a box's corners yaw it over a stiff slab, light nodes under a soft one
  // are moved sideways) the frictions' sum fell short of mu times the normal impulse and a box
  // below the friction angle kept sliding. The friction's linearisation in the slip,
  // d f / d s = -(|f| / |s|)(P_t - s s^T / |s|^2), joins the next solve. It is a linearisation,
  // valid near the slip it was taken at: it is bounded by the effective mass of the node's motion
  // relative to the body (node and dynamic partner in series), at which it would stop a slip across
  // the friction within the solve, as a stick would, and no more. Unbounded (|f| over a slip of a
  // few micrometres per second), a node whose slip had turned held a box at 1.2 m/s over a stiff
  // slab like a wall, and its rear face's contacts then pulled it back (-33 % of Coulomb's
  // distance).
  for (NodeContact& c : contacts_) {
    c.slip_resistance.setZero();
    if (c.held || c.anchored || c.state != NodeContact::State::kSlide || c.friction <= 0) continue;
    const double magnitude = c.friction_impulse.norm();
    if (magnitude <= 0) continue;
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d slip = tangentialSlip(c, v.segment<3>(3 * c.node), k.velocity);
    const double speed = slip.norm();
    if (speed <= 0) continue;
    const Eigen::Vector3d d = slip / speed;
    const double node_mass = model_->nodeMasses()[static_cast<size_t>(c.node)];
    const double relative_mass = k.dynamic ? node_mass * k.mass / (node_mass + k.mass) : node_mass;
    const double resistance = speed * relative_mass > magnitude ? magnitude / speed : relative_mass;
    c.slip_resistance = resistance * (Eigen::Matrix3d::Identity() -
                                      c.normal * c.normal.transpose() - d * d.transpose());
  }
}

void RigidContactSolver::measureFrictionShares() {
  // The split of a body's load between a face contact and the node contacts at its corners is
  // not unique where both hold the same motion: on a stiff slab they share it as a push and a
  // pull, and Coulomb bounds taken per contact from the pushes alone gave the body far more
  // friction than mu times its net normal impulse (docs/contact.md, "Sliding over nodes").
  std::vector<double> push(partners_.size(), 0.0), net(partners_.size(), 0.0);
  for (const NodeContact& c : contacts_) {
    if (c.held || c.state == NodeContact::State::kInactive) continue;
    const double lambda = c.normal.dot(product_.segment<3>(3 * c.node));
    push[static_cast<size_t>(c.partner)] += std::max(lambda, 0.0);
    net[static_cast<size_t>(c.partner)] += lambda;
  }
  for (const FaceContact& c : faces_.contacts()) {
    if (c.state == FaceContact::State::kInactive || c.determined) continue;
    const double lambda = c.normal.dot(c.impulse);
    push[static_cast<size_t>(c.partner)] += std::max(lambda, 0.0);
    net[static_cast<size_t>(c.partner)] += lambda;
  }
  for (size_t k = 0; k < partners_.size(); ++k)
    partners_[k].friction_share = push[k] > 0 ? std::clamp(net[k] / push[k], 0.0, 1.0) : 1.0;
}

}  // namespace torsion
