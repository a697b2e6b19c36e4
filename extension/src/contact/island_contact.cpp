#include "torsion/contact/island_contact.h"

#include <algorithm>
#include <array>
#include <limits>

#include "torsion/solve/pcg_iterations.h"

namespace torsion {

namespace {

// The Gauss-Seidel path's penalty, relative to the joint solve's: each body's solve sees only its
// own share of the penalty, and block Gauss-Seidel converges slowly against a stiff one (measured
// on a ball resting on a slab: factor 20 left 135 of 400 steps unconverged, 1 and 4 none; on the
// soft_stack scene 0.01 left 0.7 mm end penetration, 0.05 4.2 mm, 0.2 and 1 diverged).
constexpr double kGaussSeidelPenaltyScale = 0.01;

// Passes that move linearised gaps onto the true end-of-step surface (BodyPairContact::
// correctGaps) before a step may settle. Each is a secant step of the gap function with the
// detection's normal as its slope: on the soft cubes thrown at each other at 15 m/s
// (bullet_collide_soft) the deepest node ends 1.1 mm inside the other cube instead of 9.6 mm
// (docs/contact.md, "Fast impacts").
constexpr int kMaxPairGapCorrections = 4;

bool participates(const SurfaceContact& c) {
  return !c.determined && c.state != SurfaceContact::State::kInactive;
}

bool onSide(int node, int first, int count) {
  return node >= first && node < first + count;
}

// The contact's operator block: rho I sticking, rho n n^T + k_t (I - n n^T) sliding, so that
// sliding friction is implicit (surface_contact_set.h): -k_t u_t of the same solve's slip, never
// an impulse carried over from the last one (that explicit friction threw a block off a coarse
// slab: docs/contact.md, "Friction between FEM bodies").
Eigen::Matrix3d block(const SurfaceContact& c) {
  return SurfaceContactSet::operatorBlock(c);
}

}  // namespace

void PairContactTerm::addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  if (suspended_) return;
  for (const Side& side : sides_) {
    for (const SurfaceContact& c : side.set->contacts()) {
      if (!participates(c)) continue;
      Eigen::Vector3d u = Eigen::Vector3d::Zero();
      bool touches = false;
      for (size_t k = 0; k < 4; ++k) {
        if (!onSide(c.nodes[k], side.first, side.count)) continue;
        u += c.beta[k] * y.segment<3>(3 * (c.nodes[k] - side.first));
        touches = true;
      }
      if (!touches) continue;
      const Eigen::Vector3d f = block(c) * u;
      for (size_t k = 0; k < 4; ++k) {
        if (onSide(c.nodes[k], side.first, side.count))
          out.segment<3>(3 * (c.nodes[k] - side.first)) += c.beta[k] * f;
      }
    }
  }
}

void PairContactTerm::addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const {
  if (suspended_) return;
  for (const Side& side : sides_) {
    for (const SurfaceContact& c : side.set->contacts()) {
      if (!participates(c)) continue;
      const Eigen::Matrix3d p = block(c);
      for (size_t k = 0; k < 4; ++k) {
        if (onSide(c.nodes[k], side.first, side.count))
          blocks[static_cast<size_t>(c.nodes[k] - side.first)] += c.beta[k] * c.beta[k] * p;
      }
    }
  }
}

void IslandContactSolve::pairVelocities(const std::vector<Body>& bodies, const Pair& pair,
                                        Eigen::VectorXd& v) const {
  const Eigen::VectorXd& va = *bodies[static_cast<size_t>(pair.first)].v;
  const Eigen::VectorXd& vb = *bodies[static_cast<size_t>(pair.second)].v;
  v.resize(va.size() + vb.size());
  v.head(va.size()) = va;
  v.tail(vb.size()) = vb;
}

void IslandContactSolve::addRightHandSide(const std::vector<Body>& bodies,
                                          const std::vector<Pair>& pairs, size_t i, double dt,
                                          bool closing, Eigen::VectorXd& rhs) const {
  for (const Pair& pair : pairs) {
    const bool is_first = static_cast<size_t>(pair.first) == i;
    if (!is_first && static_cast<size_t>(pair.second) != i) continue;
    const Body& other = bodies[static_cast<size_t>(is_first ? pair.second : pair.first)];
    if (!other.present) continue;
    const int na = pair.contact->nodeCountA();
    const int first = is_first ? 0 : na;
    const int count = static_cast<int>(rhs.size() / 3);
    const int other_first = is_first ? na : 0;
    for (const SurfaceContact& c : pair.contact->set().contacts()) {
      if (!participates(c)) continue;
      // Closing: the impulse fixed at Lambda (its friction included); else as in the joint solve.
      Eigen::Vector3d r = closing ? c.multiplier : SurfaceContactSet::rightHandSideImpulse(c, dt);
      if (!closing) {
        // The other body's share of the relative velocity, from its latest solve.
        Eigen::Vector3d u_other = Eigen::Vector3d::Zero();
        for (size_t k = 0; k < 4; ++k) {
          if (!onSide(c.nodes[k], first, count))
            u_other += c.beta[k] * other.v->segment<3>(3 * (c.nodes[k] - other_first));
        }
        r -= block(c) * u_other;
      }
      for (size_t k = 0; k < 4; ++k) {
        if (onSide(c.nodes[k], first, count))
          rhs.segment<3>(3 * (c.nodes[k] - first)) += c.beta[k] * r;
      }
    }
  }
}

LinearSolveReport IslandContactSolve::solveBody(Body& body, size_t i, const Eigen::VectorXd& rhs) {
  const LinearSolveReport r =
      body.solve ? body.solve(*body.op, *body.constraints, rhs, *body.settings, *body.v)
                 : cg_[i].solve(*body.op, *body.constraints, rhs, *body.settings, *body.v);
  body.report.iterations += r.iterations;
  body.report.relative_residual = r.relative_residual;
  body.report.converged = r.converged;
  if (r.breakdown) {
    body.report.breakdown = true;
    body.report.breakdown_reason = r.breakdown_reason;
  }
  return r;
}

void IslandContactSolve::sweep(std::vector<Body>& bodies, const std::vector<Pair>& pairs, double dt,
                               bool& broke, double& moved) {
  for (size_t i = 0; i < bodies.size() && !broke; ++i) {
    Body& body = bodies[i];
    if (!body.present) continue;
    rhs_ = *body.b;
    addRightHandSide(bodies, pairs, i, dt, false, rhs_);
    previous_v_ = *body.v;
    if (solveBody(body, i, rhs_).breakdown) broke = true;
    moved = std::max(moved, dt * (*body.v - previous_v_).lpNorm<Eigen::Infinity>());
  }
}

void IslandContactSolve::addJointProduct(const std::vector<const Pair*>& live,
                                         const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  for (const Pair* pair : live) {
    const int na = pair->contact->nodeCountA();
    const int oa = offsets_[static_cast<size_t>(pair->first)];
    const int ob = offsets_[static_cast<size_t>(pair->second)];
    for (const SurfaceContact& c : pair->contact->set().contacts()) {
      if (!participates(c)) continue;
      std::array<int, 4> at{};
      Eigen::Vector3d u = Eigen::Vector3d::Zero();
      for (size_t k = 0; k < 4; ++k) {
        at[k] = c.nodes[k] < na ? oa + 3 * c.nodes[k] : ob + 3 * (c.nodes[k] - na);
        u += c.beta[k] * y.segment<3>(at[k]);
      }
      const Eigen::Vector3d f = block(c) * u;
      for (size_t k = 0; k < 4; ++k)
        out.segment<3>(at[k]) += c.beta[k] * f;
    }
  }
}

void IslandContactSolve::jointSolve(std::vector<Body>& bodies, const std::vector<const Pair*>& live,
                                    double dt, bool& broke) {
  // Offsets, and the bodies' own terms off: the whole pair term is applied here.
  offsets_.assign(bodies.size(), -1);
  int size = 0;
  const SolverSettings* settings = nullptr;
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].present) continue;
    offsets_[i] = size;
    size += static_cast<int>(bodies[i].v->size());
    bodies[i].term->setSuspended(true);
    if (settings == nullptr) settings = bodies[i].settings;
  }
  joint_b_.resize(size);
  joint_v_.resize(size);
  joint_c_.setZero(size);
  joint_inverse_.clear();
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].present) continue;
    const int o = offsets_[i], m = static_cast<int>(bodies[i].v->size());
    const NodeConstraints& constraints = constraintsOf(bodies, i);
    constraints.impose(*bodies[i].v);
    joint_v_.segment(o, m) = *bodies[i].v;
    joint_b_.segment(o, m) = rightHandSideOf(bodies, i);
    Eigen::VectorXd prescribed = Eigen::VectorXd::Zero(m);
    constraints.impose(prescribed);
    joint_c_.segment(o, m) = prescribed;
    bodies[i].op->diagonalBlocks(blocks_[i]);
    joint_inverse_.insert(joint_inverse_.end(), blocks_[i].begin(), blocks_[i].end());
  }
  // b += beta_k (Lambda - rho n g / dt); the diagonal blocks get rho beta_k^2 P.
  for (const Pair* pair : live) {
    const int na = pair->contact->nodeCountA();
    const int oa = offsets_[static_cast<size_t>(pair->first)];
    const int ob = offsets_[static_cast<size_t>(pair->second)];
    for (const SurfaceContact& c : pair->contact->set().contacts()) {
      if (!participates(c)) continue;
      const Eigen::Vector3d r = SurfaceContactSet::rightHandSideImpulse(c, dt);
      const Eigen::Matrix3d p = block(c);
      for (size_t k = 0; k < 4; ++k) {
        const int at = c.nodes[k] < na ? oa + 3 * c.nodes[k] : ob + 3 * (c.nodes[k] - na);
        joint_b_.segment<3>(at) += c.beta[k] * r;
        joint_inverse_[static_cast<size_t>(at / 3)] += c.beta[k] * c.beta[k] * p;
      }
    }
  }
  for (Eigen::Matrix3d& block : joint_inverse_)
    block = block.inverse().eval();

  // Each body's constraints filter its own slice.
  auto filter = [&](Eigen::VectorXd& x) {
    for (size_t i = 0; i < bodies.size(); ++i) {
      if (!bodies[i].present) continue;
      const NodeConstraints& constraints = constraintsOf(bodies, i);
      for (int node = 0; node < constraints.nodeCount(); ++node) {
        if (!constraints.isConstrained(node)) continue;
        const int at = offsets_[i] + 3 * node;
        x.segment<3>(at) = constraints.filterNode(node, x.segment<3>(at));
      }
    }
  };
  auto applyUnfiltered = [&](const Eigen::VectorXd& y, Eigen::VectorXd& out) {
    out.resize(y.size());
    for (size_t i = 0; i < bodies.size(); ++i) {
      if (!bodies[i].present) continue;
      const int o = offsets_[i], m = static_cast<int>(bodies[i].v->size());
      rhs_ = y.segment(o, m);
      bodies[i].op->multiply(rhs_, previous_v_);
      out.segment(o, m) = previous_v_;
    }
    addJointProduct(live, y, out);
  };
  auto apply = [&](const Eigen::VectorXd& y, Eigen::VectorXd& out) {
    applyUnfiltered(y, out);
    filter(out);
  };
  auto precondition = [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) {
    out.resize(in.size());
    for (size_t n = 0; n < joint_inverse_.size(); ++n)
      out.segment<3>(3 * static_cast<Eigen::Index>(n)) =
          joint_inverse_[n] * in.segment<3>(3 * static_cast<Eigen::Index>(n));
    filter(out);
  };
  apply(joint_c_, joint_q_);
  joint_r_ = joint_b_ - joint_q_;
  filter(joint_r_);
  const double reference = joint_r_.norm();
  apply(joint_v_, joint_q_);
  joint_r_ = joint_b_ - joint_q_;
  filter(joint_r_);
  const LinearSolveReport r =
      pcgIterations(apply, precondition, reference, *settings, joint_v_, joint_r_, joint_scratch_);
  // The impulses the constraints leave on their nodes (rigid node contacts' active sets): the
  // system's residual, which the projected CG drives to zero on the free components only.
  bool rigid = false;
  for (const Body& body : bodies)
    rigid = rigid || (body.present && body.rigid != nullptr);
  if (rigid) {
    applyUnfiltered(joint_v_, joint_impulse_);
    joint_impulse_ -= joint_b_;
  }
  for (size_t i = 0; i < bodies.size(); ++i) {
    if (!bodies[i].present) continue;
    *bodies[i].v = joint_v_.segment(offsets_[i], static_cast<int>(bodies[i].v->size()));
    bodies[i].term->setSuspended(false);
    bodies[i].report.iterations += r.iterations;
    bodies[i].report.relative_residual = r.relative_residual;
    bodies[i].report.converged = r.converged;
    if (r.breakdown) {
      bodies[i].report.breakdown = true;
      bodies[i].report.breakdown_reason = r.breakdown_reason;
    }
  }
  if (r.breakdown) broke = true;
}

void IslandContactSolve::prepareRigidContacts(std::vector<Body>& bodies) {
  rigid_constraints_.resize(bodies.size());
  rigid_b_.resize(bodies.size());
  for (size_t i = 0; i < bodies.size(); ++i) {
    const Body& body = bodies[i];
    if (body.present && body.rigid != nullptr)
      body.rigid->islandConstraints(*body.b, rigid_constraints_[i], rigid_b_[i]);
  }
}

bool IslandContactSolve::updateRigidContacts(std::vector<Body>& bodies) {
  bool changed = false;
  for (size_t i = 0; i < bodies.size(); ++i) {
    Body& body = bodies[i];
    if (!body.present || body.rigid == nullptr) continue;
    const Eigen::Index m = body.v->size();
    // The pair contacts' impulses are in the joint residual's right-hand side (b) and product
    // alike, so what is left on a node is its rigid contact's impulse (and its hand's, if held).
    rhs_ = joint_impulse_.segment(offsets_[i], m);
    if (body.rigid->updateIslandActiveSet(*body.v, rhs_)) changed = true;
  }
  return changed;
}

IslandContactStats IslandContactSolve::solve(std::vector<Body>& bodies,
                                             const std::vector<Pair>& pairs, double dt) {
  IslandContactStats stats;
  cg_.resize(bodies.size());
  blocks_.resize(bodies.size());
  std::vector<const Pair*> live;  // pairs whose two bodies both prepared their step
  for (const Pair& pair : pairs) {
    if (bodies[static_cast<size_t>(pair.first)].present &&
        bodies[static_cast<size_t>(pair.second)].present)
      live.push_back(&pair);
  }
  const BodyContactSettings settings =
      pairs.empty() ? BodyContactSettings{} : pairs.front().contact->settings();

  // Contacts whose four nodes are all prescribed sit the solves out.
  for (const Pair* pair : live) {
    const Body& a = bodies[static_cast<size_t>(pair->first)];
    const Body& b = bodies[static_cast<size_t>(pair->second)];
    const int na = pair->contact->nodeCountA();
    pair->contact->set().markDetermined([&](int node) {
      return node < na ? a.constraints->kind(node) == NodeConstraints::Kind::kFull
                       : b.constraints->kind(node - na) == NodeConstraints::Kind::kFull;
    });
  }
  for (Body& body : bodies) {
    if (body.present && body.rigid != nullptr) body.rigid->beginIslandSolve(*body.constraints);
  }
  // One joint solve when no body brings a solve of its own (rigid contacts with a dynamic
  // partner, self-contact); node contacts with prescribed rigid partners join it.
  bool joint = true;
  for (const Body& body : bodies)
    if (body.present && body.solve) joint = false;
  // Penalties from each body's system without the pair term.
  for (size_t i = 0; i < bodies.size(); ++i) {
    Body& body = bodies[i];
    body.report = LinearSolveReport{};
    if (!body.present) continue;
    body.term->setSuspended(true);
    body.op->diagonalBlocks(blocks_[i]);
    body.term->setSuspended(false);
  }
  for (const Pair* pair : live) {
    const auto& ba = blocks_[static_cast<size_t>(pair->first)];
    const auto& bb = blocks_[static_cast<size_t>(pair->second)];
    pair_blocks_.assign(ba.begin(), ba.end());
    pair_blocks_.insert(pair_blocks_.end(), bb.begin(), bb.end());
    pair->contact->set().setPenalties(
        pair_blocks_, settings.penalty_factor * (joint ? 1.0 : kGaussSeidelPenaltyScale));
    // A sliding contact's starting k_t (BodyPairContact::detect) at most its penalty.
    for (SurfaceContact& c : pair->contact->set().contacts())
      c.tangential_stiffness = std::min(c.tangential_stiffness, c.penalty);
  }

  double min_tolerance = std::numeric_limits<double>::infinity();
  for (const Pair* pair : live)
    min_tolerance = std::min(min_tolerance, pair->contact->gapTolerance());
  bool settled = false, broke = false, rigid_settled = true;
  double best_error = 0;
  int worse = 0, corrections = 0, first_round = 0;
  for (int round = 0; round < settings.max_iterations && !broke; ++round) {
    double moved = 0;
    bool rigid_changed = false;
    if (joint) {
      prepareRigidContacts(bodies);
      jointSolve(bodies, live, dt, broke);
      if (!broke) rigid_changed = updateRigidContacts(bodies);
      rigid_settled = !rigid_changed;
    } else {
      sweep(bodies, pairs, dt, broke, moved);
    }
    ++stats.iterations;
    if (broke) break;
    // A Gauss-Seidel sweep saw the others' velocities of their previous solve: settled only once
    // no velocity moves a node by more than the tolerance over the step from one sweep to the
    // next (the joint solve sees them all at once, but settles only with the rigid contacts'
    // active sets).
    settled = joint ? !rigid_changed : (round > 0 && moved <= min_tolerance);
    for (const Pair* pair : live) {
      pairVelocities(bodies, *pair, pair_v_);
      const double tolerance = pair->contact->gapTolerance();
      // Activation below a tenth of the tolerance: a contact hovering at zero gap does not flip.
      if (!pair->contact->set().update(pair_v_, dt, 0.1 * tolerance, tolerance)) settled = false;
    }
    // Settled, or at least every linearised gap within its tolerance (sliding friction may take
    // the rest of the updates to settle, or not settle): measure the gaps on the true end
    // positions, and go on where a node would end behind the moved surface.
    double gap_error = 0;
    for (const Pair* pair : live)
      gap_error = std::max(gap_error, pair->contact->set().maxGapError());
    if ((settled || gap_error <= min_tolerance) && corrections < kMaxPairGapCorrections) {
      int shifted = 0;
      for (const Pair* pair : live) {
        pairVelocities(bodies, *pair, pair_v_);
        shifted += pair->contact->correctGaps(pair_v_, dt, pair->contact->gapTolerance());
      }
      if (shifted > 0) {
        ++corrections;
        settled = false;
        first_round = round + 1;  // the safeguard starts over on the shifted gaps
        continue;
      }
    }
    if (settled) break;
    // Safeguard (as for self-contact): where the sweeps and updates do not contract (contacts
    // contradicting each other, an inexact sweep against a stiff penalty) the best round so far is
    // kept, and three worse ones in a row end the loop with it (reported as not converged).
    double error = 0;
    for (const Pair* pair : live)
      error = std::max(error, pair->contact->set().maxGapError());
    if (round == first_round || error < best_error) {
      best_error = error;
      best_v_.resize(bodies.size());
      best_contacts_.resize(live.size());
      for (size_t i = 0; i < bodies.size(); ++i)
        if (bodies[i].present) best_v_[i] = *bodies[i].v;
      for (size_t p = 0; p < live.size(); ++p)
        best_contacts_[p] = live[p]->contact->set().contacts();
      worse = 0;
    } else if (error > min_tolerance && ++worse >= 3) {
      for (size_t i = 0; i < bodies.size(); ++i)
        if (bodies[i].present) *bodies[i].v = best_v_[i];
      for (size_t p = 0; p < live.size(); ++p)
        live[p]->contact->set().contacts() = best_contacts_[p];
      break;
    }
  }

  // Closing solve (Gauss-Seidel path): the impulses fixed at Lambda, equal and opposite on the
  // two bodies. The joint solve needs none: each of its impulses acts on both bodies at once.
  for (size_t i = 0; i < bodies.size() && !broke && !joint; ++i) {
    Body& body = bodies[i];
    if (!body.present) continue;
    body.term->setSuspended(true);
    rhs_ = *body.b;
    addRightHandSide(bodies, pairs, i, dt, true, rhs_);
    if (solveBody(body, i, rhs_).breakdown) broke = true;
    body.term->setSuspended(false);
  }

  // The rigid node contacts' impulses and end gaps, as their own solve ends.
  for (Body& body : bodies) {
    if (body.present && body.rigid != nullptr) body.rigid->endIslandSolve(*body.v, rigid_settled);
  }

  // The end gaps on the velocities the bodies keep.
  bool within = true;
  for (const Pair* pair : live) {
    pairVelocities(bodies, *pair, pair_v_);
    const double tolerance = pair->contact->gapTolerance();
    stats.gap_tolerance = std::max(stats.gap_tolerance, tolerance);
    for (const SurfaceContact& c : pair->contact->set().contacts()) {
      ++stats.candidates;
      if (c.determined) continue;
      Eigen::Vector3d u = Eigen::Vector3d::Zero();
      for (size_t k = 0; k < 4; ++k)
        u += c.beta[k] * pair_v_.segment<3>(3 * c.nodes[k]);
      const double penetration = -(c.gap + dt * c.normal.dot(u));
      stats.max_end_penetration = std::max(stats.max_end_penetration, penetration);
      if (penetration > tolerance) within = false;
      if (c.state == SurfaceContact::State::kInactive) continue;
      ++stats.active;
      if (c.state == SurfaceContact::State::kStick) ++stats.sticking;
      stats.normal_impulse += c.normal.dot(c.multiplier);
    }
  }
  stats.converged = settled && within && !broke;
  return stats;
}

}  // namespace torsion
