#include "torsion/contact/face_contacts.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/contact/face_distance.h"
#include "torsion/contact/query/feature_contacts.h"
#include "torsion/contact/shape_distance.h"

namespace torsion {

namespace {

// A weight below this puts the contact point on the opposite edge (or corner): the contact is the
// edge's (or the node's), whichever triangle found it.
constexpr double kEdgeWeight = 1e-6;
constexpr int kMaxStalls = 3;
// A face point must come this fraction of the detection reach nearer the shape than its nodes'
// interpolated distances to be a contact of its own (round-off on flat-on-flat is far below).
constexpr double kDuplicateMargin = 1e-3;
constexpr int kMaxSwitches = 1;
constexpr int kMaxFaceFrictionRefinements = 8;
// m/s: a sliding face carried past the body faster than this by its friction sticks at once.
constexpr double kCarriedPastSpeed = 0.01;
// m: round-off between the nearest pair's and a supporting plane's predicted end gaps.
constexpr double kPlaneChoiceMargin = 1e-9;

// Whether the contact takes part in this solve.
bool participates(const FaceContact& c) {
  return c.state != FaceContact::State::kInactive && !c.determined;
}

Eigen::Matrix3d projector(const FaceContact& c) {
  return c.state == FaceContact::State::kStick ? Eigen::Matrix3d::Identity()
                                               : Eigen::Matrix3d(c.normal * c.normal.transpose());
}

// kg: the contact's impulse per unit relative velocity in the solve. A stuck face's penalty acts
// in all three directions, a sliding face's along the normal only, plus its friction's resistance
// to a slip across the friction's direction (FaceContact::slip_resistance).
Eigen::Matrix3d stiffness(const FaceContact& c) {
  return c.penalty * projector(c) + c.slip_resistance;
}

// Whether the triangle is better held against the rigid shape's supporting plane that faces it
// (normal minus the triangle's) than along the nearest pair (f), by the end gaps the predicted
// motion leaves (the nodes' velocities, the rigid body's after Bullet's integration). A triangle
// on a flat surface just ahead of a sliding box is nearest the box's front face, and the end gap
// along that horizontal normal stops the box as at a wall; the box's bottom edge will pass over
// the triangle, whose nodes hold it against the bottom plane themselves (node contacts take the
// same plane, rigid_contact.cpp), so such a face contact is left out. At rest the nearest pair
// is never farther than a supporting plane: nothing changes.
bool supportPlaneLeavesMore(const btCollisionShape& shape, const btTransform& transform,
                            const FemState& state, const Triangle& tri, const FacePoint& f,
                            const RigidPartner& p, double dt) {
  const Eigen::Vector3d a = state.position(tri[0]), b = state.position(tri[1]),
                        c = state.position(tri[2]);
  const Eigen::Vector3d outward = (b - a).cross(c - a);
  if (outward.squaredNorm() == 0) return false;
  const Eigen::Vector3d rigid = pointVelocity(p.entry_velocity, f.shape_point - p.com);
  Eigen::Vector3d face_velocity = Eigen::Vector3d::Zero();
  for (size_t j = 0; j < 3; ++j)
    face_velocity += f.barycentric[static_cast<Eigen::Index>(j)] * state.velocity(tri[j]);
  const Eigen::Vector3d into = -outward.normalized();
  // Only the motion along the plane predicts which side the face ends on: across it, the rigid
  // body's predicted velocity carries the step's gravity, which the contacts under it cancel.
  Eigen::Vector3d slip = face_velocity - rigid;
  slip -= into * into.dot(slip);
  const double end_nearest = f.distance + dt * f.normal.dot(slip);
  double end_plane = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < 3; ++j) {
    const std::optional<SurfacePoint> plane =
        supportPlaneDistance(shape, transform, state.position(tri[j]), into);
    if (!plane) return false;
    end_plane = std::min(end_plane, plane->distance);
  }
  return end_plane > end_nearest + kPlaneChoiceMargin;
}

}  // namespace

FaceContactSet::FaceContactSet(const TetMesh& mesh) : triangles_(mesh.surfaceTriangles()) {
  const int n = mesh.nodeCount();
  node_triangle_start_.assign(static_cast<size_t>(n) + 1, 0);
  for (const Triangle& t : triangles_) {
    for (int node : t)
      ++node_triangle_start_[static_cast<size_t>(node) + 1];
  }
  for (int i = 0; i < n; ++i)
    node_triangle_start_[static_cast<size_t>(i) + 1] +=
        node_triangle_start_[static_cast<size_t>(i)];
  node_triangles_.resize(static_cast<size_t>(node_triangle_start_.back()));
  std::vector<int> fill(node_triangle_start_.begin(), node_triangle_start_.end() - 1);
  for (size_t t = 0; t < triangles_.size(); ++t) {
    for (int node : triangles_[t])
      node_triangles_[static_cast<size_t>(fill[static_cast<size_t>(node)]++)] = static_cast<int>(t);
  }
  triangle_stamp_.assign(triangles_.size(), 0);
}

void FaceContactSet::beginStep(const std::vector<RigidPartner>& partners) {
  previous_.clear();
  for (const FaceContact& c : contacts_) {
    if (c.state == FaceContact::State::kInactive) continue;
    // A stalled contact's multiplier grew against constraints that left it no room: carried
    // over, it would grow again each step without bound.
    const Eigen::Vector3d carried = c.stalls > kMaxStalls ? Eigen::Vector3d::Zero() : c.multiplier;
    previous_[{c.key, partners[static_cast<size_t>(c.partner)].object}] = {c.state, carried};
  }
  contacts_.clear();
  features_.clear();
  index_.clear();
}

double FaceContactSet::longestEdge(const FemState& state) const {
  double longest = 0;
  for (const Triangle& t : triangles_) {
    for (size_t k = 0; k < 3; ++k) {
      longest = std::max(longest, (state.position(t[k]) - state.position(t[(k + 1) % 3])).norm());
    }
  }
  return longest;
}

void FaceContactSet::detect(const FemState& state, const NodeConstraints& held,
                            const std::vector<int>& nearby_nodes, const btCollisionShape& shape,
                            const btTransform& transform, const Eigen::Vector3d& lo,
                            const Eigen::Vector3d& hi, double reach, double dt, int partner,
                            const RigidPartner& p, double friction,
                            const std::vector<char>& glued) {
  ++stamp_;
  const Eigen::Vector3d pad = Eigen::Vector3d::Constant(reach);
  const std::optional<PolyhedronFeatures> polyhedron = polyhedronFeatures(shape, transform);
  std::optional<FeatureContactCollector> features;
  if (polyhedron && !p.supported) features.emplace(*polyhedron, reach, partner, p, friction);
  for (int node : nearby_nodes) {
    for (int k = node_triangle_start_[static_cast<size_t>(node)];
         k < node_triangle_start_[static_cast<size_t>(node) + 1]; ++k) {
      const int t = node_triangles_[static_cast<size_t>(k)];
      if (triangle_stamp_[static_cast<size_t>(t)] == stamp_) continue;
      triangle_stamp_[static_cast<size_t>(t)] = stamp_;
      const Triangle& tri = triangles_[static_cast<size_t>(t)];
      const Eigen::Vector3d a = state.position(tri[0]), b = state.position(tri[1]),
                            c = state.position(tri[2]);
      const Eigen::Vector3d tlo = a.cwiseMin(b).cwiseMin(c), thi = a.cwiseMax(b).cwiseMax(c);
      if ((tlo.array() > (hi + pad).array()).any() || (thi.array() < (lo - pad).array()).any())
        continue;
      bool all_held = true, on_glue = false;
      for (int node_id : tri) {
        all_held = all_held && held.kind(node_id) == NodeConstraints::Kind::kFull;
        on_glue = on_glue || (!glued.empty() && glued[static_cast<size_t>(node_id)] != 0);
      }
      if (on_glue) continue;
      if (all_held && !p.dynamic) continue;
      if (features) features->addTriangle(tri, a, b, c);
      // A supported partner (resting on the ground: coupled explicitly, one step late) gets node
      // contacts only. Face contacts at its edges, with their levers and oblique normals, spun a
      // box squeezed under a deformable faster each step through that explicit coupling (its
      // rotation is resolved against the ground by Bullet only the step after).
      if (p.supported) continue;
      const std::optional<FacePoint> f = shapeToTriangle(shape, transform, a, b, c, reach);
      if (!f || f->distance > reach) continue;
      // At a corner: the node's own contact measures the same distance.
      if (f->barycentric.maxCoeff() > 1 - kEdgeWeight) continue;
      // A face point no nearer the shape than its nodes' own distances, interpolated, is held by
      // the node contacts (a flat rigid face on a flat soft face): a face contact there would only
      // duplicate them, and duplicates slow the active set. What is left are rigid features that
      // come nearer between the nodes than at them: corners, edges, curved shapes.
      double interpolated = 0;
      for (size_t j = 0; j < 3; ++j) {
        const std::optional<SurfacePoint> d =
            signedDistance(shape, transform, state.position(tri[j]), reach);
        interpolated += f->barycentric[static_cast<Eigen::Index>(j)] *
                        (d ? d->distance : std::numeric_limits<double>::infinity());
      }
      if (f->distance >= interpolated - kDuplicateMargin * reach) continue;
      if (supportPlaneLeavesMore(shape, transform, state, tri, *f, p, dt)) continue;
      FaceContact fc;
      fc.nodes = {tri[0], tri[1], tri[2]};
      fc.weights = f->barycentric;
      // Sorted nodes of non-zero weight, -1 padded (no per-triangle allocation: a hot loop).
      fc.key = {-1, -1, -1};
      size_t used = 0;
      for (size_t j = 0; j < 3; ++j) {
        if (fc.weights[static_cast<Eigen::Index>(j)] > kEdgeWeight) fc.key[used++] = tri[j];
      }
      std::sort(fc.key.begin(), fc.key.begin() + static_cast<std::ptrdiff_t>(used));
      fc.partner = partner;
      fc.normal = f->normal;
      fc.gap = f->distance;
      fc.lever = f->shape_point - p.com;
      fc.friction = friction;
      const auto found = index_.find({fc.key, partner});
      if (found != index_.end()) {
        // An edge seen from its two triangles: keep the nearer reading.
        FaceContact& existing = contacts_[static_cast<size_t>(found->second)];
        if (fc.gap < existing.gap) {
          fc.state = existing.state;
          fc.multiplier = existing.multiplier;
          existing = fc;
        }
        continue;
      }
      const auto remembered = previous_.find({fc.key, p.object});
      if (remembered != previous_.end()) {
        fc.state = fc.friction > 0 ? remembered->second.state : FaceContact::State::kSlide;
        fc.multiplier = remembered->second.multiplier;
      }
      index_[{fc.key, partner}] = static_cast<int>(contacts_.size());
      contacts_.push_back(fc);
    }
  }
  if (features) features->appendTo(features_);
}

std::vector<FaceContact::State> FaceContactSet::states() const {
  std::vector<FaceContact::State> states;
  states.reserve(contacts_.size());
  for (const FaceContact& c : contacts_)
    states.push_back(c.state);
  return states;
}

void FaceContactSet::restoreStates(const std::vector<FaceContact::State>& states) {
  for (size_t c = 0; c < contacts_.size() && c < states.size(); ++c)
    contacts_[c].state = states[c];
}

void FaceContactSet::setPenalties(const std::vector<Eigen::Matrix3d>& diagonal_blocks,
                                  double scale) {
  for (FaceContact& c : contacts_) {
    double compliance = 0;  // 1 / kg: the face point's velocity change per unit impulse along n
    for (size_t j = 0; j < 3; ++j) {
      const double w = c.weights[static_cast<Eigen::Index>(j)];
      if (w <= 0) continue;
      compliance +=
          w * w *
          c.normal.dot(diagonal_blocks[static_cast<size_t>(c.nodes[j])].ldlt().solve(c.normal));
    }
    c.penalty = compliance > 0 ? scale / compliance : 0;
  }
}

Eigen::Vector3d FaceContactSet::relativeVelocity(const FaceContact& c, const Eigen::VectorXd& v,
                                                 const Eigen::Vector3d& rigid) const {
  Eigen::Vector3d u = -rigid;
  for (size_t j = 0; j < 3; ++j)
    u += c.weights[static_cast<Eigen::Index>(j)] * v.segment<3>(3 * c.nodes[j]);
  return u;
}

void FaceContactSet::addProduct(const Eigen::VectorXd& v, const Eigen::VectorXd& q,
                                const std::vector<RigidPartner>& partners, int rigid_offset,
                                Eigen::VectorXd& node_out, Eigen::VectorXd& rigid_out) const {
  for (const FaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const RigidPartner& k = partners[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d rigid =
        k.dynamic ? pointVelocity(q.segment<6>(k.unknown), c.lever) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d y = stiffness(c) * relativeVelocity(c, v, rigid);
    for (size_t j = 0; j < 3; ++j)
      node_out.segment<3>(3 * c.nodes[j]) += c.weights[static_cast<Eigen::Index>(j)] * y;
    if (k.dynamic) rigid_out.segment<6>(k.unknown - rigid_offset) -= pointWrench(y, c.lever);
  }
}

void FaceContactSet::addRightHandSide(const Eigen::VectorXd& prescribed,
                                      const std::vector<RigidPartner>& partners, double dt,
                                      int rigid_offset, Eigen::VectorXd& node_rhs,
                                      Eigen::VectorXd& rigid_rhs) const {
  for (const FaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const RigidPartner& k = partners[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d rigid =
        k.dynamic ? Eigen::Vector3d::Zero() : pointVelocity(k.entry_velocity, c.lever);
    const Eigen::Vector3d h0 = relativeVelocity(c, prescribed, rigid) + c.normal * (c.gap / dt);
    const Eigen::Vector3d y = c.multiplier - stiffness(c) * h0;
    for (size_t j = 0; j < 3; ++j)
      node_rhs.segment<3>(3 * c.nodes[j]) += c.weights[static_cast<Eigen::Index>(j)] * y;
    if (k.dynamic) rigid_rhs.segment<6>(k.unknown - rigid_offset) -= pointWrench(y, c.lever);
  }
}

void FaceContactSet::addPreconditioner(std::vector<Eigen::Matrix3d>& node_blocks,
                                       std::vector<Eigen::Matrix<double, 6, 6>>& rigid_blocks,
                                       const std::vector<RigidPartner>& partners) const {
  for (const FaceContact& c : contacts_) {
    if (!participates(c)) continue;
    const Eigen::Matrix3d P = stiffness(c);
    for (size_t j = 0; j < 3; ++j) {
      const double w = c.weights[static_cast<Eigen::Index>(j)];
      node_blocks[static_cast<size_t>(c.nodes[j])] += w * w * P;
    }
    if (partners[static_cast<size_t>(c.partner)].dynamic) {
      const Eigen::Matrix<double, 3, 6> J = pointJacobian(c.lever);
      rigid_blocks[static_cast<size_t>(c.partner)] += J.transpose() * P * J;
    }
  }
}

double FaceContactSet::endGap(const FaceContact& c, const Eigen::VectorXd& v,
                              const std::vector<RigidPartner>& partners, double dt) const {
  const Eigen::Vector3d rigid =
      pointVelocity(partners[static_cast<size_t>(c.partner)].velocity, c.lever);
  return c.gap + dt * c.normal.dot(relativeVelocity(c, v, rigid));
}

void FaceContactSet::takeImpulses(const Eigen::VectorXd& v,
                                  const std::vector<RigidPartner>& partners, double dt,
                                  Eigen::VectorXd& node_impulse) {
  for (FaceContact& c : contacts_) {
    if (!participates(c)) {
      c.impulse.setZero();
      continue;
    }
    const Eigen::Vector3d rigid =
        pointVelocity(partners[static_cast<size_t>(c.partner)].velocity, c.lever);
    const Eigen::Vector3d h = relativeVelocity(c, v, rigid) + c.normal * (c.gap / dt);
    c.impulse = c.multiplier - stiffness(c) * h;
    for (size_t j = 0; j < 3; ++j)
      node_impulse.segment<3>(3 * c.nodes[j]) -=
          c.weights[static_cast<Eigen::Index>(j)] * c.impulse;
  }
}

bool FaceContactSet::update(const Eigen::VectorXd& v, const std::vector<RigidPartner>& partners,
                            double dt, double activation_tolerance, double gap_tolerance) {
  bool again = false;
  for (FaceContact& c : contacts_) {
    const Eigen::Vector3d rigid =
        pointVelocity(partners[static_cast<size_t>(c.partner)].velocity, c.lever);
    const Eigen::Vector3d h = relativeVelocity(c, v, rigid) + c.normal * (c.gap / dt);
    const double end_gap = dt * c.normal.dot(h);
    if (c.determined) continue;
    if (c.state == FaceContact::State::kInactive) {
      // Within the stated tolerance a face stays out: activating an edge contact for a
      // micrometre, releasing it the next solve, and the nodes' friction following each time,
      // was most of the active-set iterations of rigid_mix.
      if (end_gap < -std::max(activation_tolerance, gap_tolerance)) {
        // A face that a body sliding over the surface (RigidPartner::sliding) slips over by more
        // than the gap tolerance this step starts sliding, as node contacts do
        // (rigid_contact_active_set.cpp); its friction follows from the next update. Started
        // stuck, its penalty glued a box sliding over a soft slab to each new triangle for a
        // solve, the face then pulled, was released and added again, and the loop cycled to its
        // cap on those two sets, ending the step on a glued solve (docs/contact.md, "Sliding over
        // nodes"). Other faces start stuck: a landing or resting body's (Poisson's slips).
        // The slip with this solve's velocities or the body's before the step (as for nodes).
        const RigidPartner& k = partners[static_cast<size_t>(c.partner)];
        const Eigen::Vector3d entry_h =
            relativeVelocity(c, v, pointVelocity(k.entry_velocity, c.lever));
        const double slip = std::max((h - c.normal * c.normal.dot(h)).norm(),
                                     (entry_h - c.normal * c.normal.dot(entry_h)).norm());
        const bool slipping =
            k.sliding && dt * slip > std::max(activation_tolerance, gap_tolerance);
        c.state =
            c.friction > 0 && !slipping ? FaceContact::State::kStick : FaceContact::State::kSlide;
        c.multiplier.setZero();
        again = true;
      }
      continue;
    }
    // A violation that does not shrink is a constraint the others leave no room for (a rigid
    // body squeezed between held faces, or nodes held by another body): after kMaxStalls
    // updates its multiplier stops growing for the rest of the step, and its rigid partner
    // takes the violation instead of an unbounded impulse.
    const double violation = std::abs(end_gap);
    if (c.last_violation > 0 && violation > gap_tolerance && violation > 0.95 * c.last_violation)
      ++c.stalls;
    c.last_violation = violation;
    if (c.stalls > kMaxStalls) continue;
    // Uzawa: the multiplier moves by -rho h, then onto Coulomb's cone.
    const Eigen::Vector3d trial = c.multiplier - c.penalty * h;
    const double lambda = c.normal.dot(trial);
    if (lambda <= 0) {
      ++c.releases;
      c.state = FaceContact::State::kInactive;
      c.multiplier.setZero();
      again = true;
      continue;
    }
    const Eigen::Vector3d tangential = trial - c.normal * lambda;
    const double bound =
        partners[static_cast<size_t>(c.partner)].friction_share * c.friction * lambda;
    const FaceContact::State before = c.state;
    const Eigen::Vector3d applied = c.multiplier - c.normal * c.normal.dot(c.multiplier);
    const double applied_friction = applied.norm();
    const Eigen::Vector3d slip = h - c.normal * c.normal.dot(h);
    const bool overshot = before == FaceContact::State::kSlide && c.friction > 0 &&
                          applied_friction > 0 && slip.dot(applied) > 0;
    const bool carried_past = slip.norm() > kCarriedPastSpeed;
    if (overshot && ((carried_past && c.switches < kMaxSwitches) ||
                     (c.switches >= kMaxSwitches && tangential.norm() > bound))) {
      // The slip turned along the friction the solve applied: that friction was more than enough
      // to stop it within the step (a light face under a heavy sliding body: the friction carries
      // its nodes past the body). Projected onto the cone along the new slip, the friction would
      // flip back and forth with each solve, and the step could end on either sign (a box
      // sliding over a soft slab was pushed downhill, 1 deg below the friction angle it crept
      // 3 cm in 1 s). Instead, when the face was carried past the body faster than
      // kCarriedPastSpeed, it sticks, from the applied friction within this solve's cone (for
      // every overshoot, a box dropped onto a slope below the friction angle crept 7 mm in 1 s);
      // past the switch budget, where Uzawa's trial would leave the cone on the other side, it
      // keeps its friction (direction and magnitude), brought within this solve's cone: a fixed
      // friction bounded by mu lambda. (Uzawa's update along the direction, less rho times the
      // slip along it, took the friction to zero, and the next solve back onto the cone: the same
      // cycle.) A trial within the cone is taken as before (below).
      const Eigen::Vector3d d = applied / applied_friction;
      const double magnitude = std::min(applied_friction, bound);
      c.multiplier = c.normal * lambda + magnitude * d;
      if (c.switches < kMaxSwitches) {
        c.state = FaceContact::State::kStick;
        ++c.switches;
      } else if (applied_friction - magnitude > 1e-2 * bound &&
                 c.friction_refinements++ < kMaxFaceFrictionRefinements) {
        again = true;
      }
      if (c.state != before || violation > gap_tolerance) again = true;
      continue;
    }
    if (c.friction > 0 && tangential.norm() <= bound) {
      // Within the cone: sticks, or, after kMaxSwitches slide-to-stick switches this step (they
      // can cycle: neighbouring contacts' tangential impulses are coupled through the body),
      // keeps sliding with the trial's friction, which is within mu lambda (Uzawa on the
      // tangential multiplier alone).
      if (before != FaceContact::State::kSlide || c.switches < kMaxSwitches)
        c.state = FaceContact::State::kStick;
      c.multiplier = trial;
    } else {
      c.state = FaceContact::State::kSlide;
      c.multiplier = c.normal * lambda;
      if (c.friction > 0) c.multiplier += bound * tangential.normalized();
    }
    // Another solve while the end gap is off, or for a stick/slide switch. Stick to slide always
    // solves again: a stuck face's impulse in the solve just done (Lambda - rho h, the trial) is
    // beyond the cone, and a step must not end on it (a sliding box's edge glued to each new
    // triangle it reached). The way back is bounded above (kMaxSwitches). The stick's slip is
    // not a criterion: its penalty keeps it at the scale of the gap tolerance.
    if (c.state != before) {
      if (c.state == FaceContact::State::kStick) ++c.switches;
      again = true;
    }
    if (violation > gap_tolerance) again = true;
    // A sliding face's friction was set from the multiplier of the solve before; its normal
    // impulse in this solve (Lambda - rho h) can differ by rho times an end gap still within the
    // gap tolerance, a large part of a light body's weight on a soft slab. Until they agree
    // within 1 % (or kMaxFaceFrictionRefinements solves) the loop goes on, as for node friction.
    if (c.state == FaceContact::State::kSlide && before == FaceContact::State::kSlide &&
        c.friction > 0 && std::abs(bound - applied_friction) > 1e-2 * bound &&
        c.friction_refinements++ < kMaxFaceFrictionRefinements)
      again = true;
  }
  setSlipResistance(v, partners);
  return again;
}

void FaceContactSet::setSlipResistance(const Eigen::VectorXd& v,
                                       const std::vector<RigidPartner>& partners) {
  // Coulomb's sliding friction is -mu lambda s / |s| of the slip s the solve ends with, but each
  // solve applies a friction fixed beforehand (the last update's), along the slip of the solve
  // before. On a soft slab a sliding box's edge moves the light nodes under it sideways as it
  // indents them, so each face's slip, and with it the next solve's friction, turned by up to
  // 45 deg from step to step: the frictions' sum along the slope fell to 0.28 of the normal
  // impulse (mu = 0.3), and a box 1 deg below the friction angle kept sliding. The friction's
  // linearisation in the slip, d f / d s = -(|f| / |s|)(P_t - d d^T) (d the slip's direction),
  // goes into the next solve: a slip across the friction meets the friction it would turn, and
  // the friction's direction follows the slip inside the solve. It is bounded by the penalty of a
  // stuck face (a slip slower than |f| / rho would have the face stick).
  for (FaceContact& c : contacts_) {
    c.slip_resistance.setZero();
    if (c.determined || c.state != FaceContact::State::kSlide || c.friction <= 0) continue;
    const Eigen::Vector3d friction = c.multiplier - c.normal * c.normal.dot(c.multiplier);
    const double magnitude = friction.norm();
    if (magnitude <= 0) continue;
    const Eigen::Vector3d rigid =
        pointVelocity(partners[static_cast<size_t>(c.partner)].velocity, c.lever);
    const Eigen::Vector3d h = relativeVelocity(c, v, rigid);
    const Eigen::Vector3d slip = h - c.normal * c.normal.dot(h);
    const double speed = slip.norm();
    if (speed <= 0) continue;
    const double resistance = speed * c.penalty > magnitude ? magnitude / speed : c.penalty;
    const Eigen::Vector3d d = slip / speed;
    c.slip_resistance = resistance * (Eigen::Matrix3d::Identity() -
                                      c.normal * c.normal.transpose() - d * d.transpose());
  }
}

}  // namespace torsion
