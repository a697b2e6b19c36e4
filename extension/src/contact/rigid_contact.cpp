#include "torsion/contact/rigid_contact.h"

#include <BulletCollision/BroadphaseCollision/btDbvt.h>
#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <LinearMath/btTransformUtil.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/contact/shape_distance.h"
#include "torsion/solve/pcg_iterations.h"

namespace torsion {

namespace {

constexpr int kMaxSlipsPerStep = 2;
constexpr int kMaxFrictionRefinements = 8;
// m: a supporting plane replaces the nearest feature's only if it leaves a larger predicted end
// gap by more than round-off (at rest the two agree).
constexpr double kPlaneChoiceMargin = 1e-9;

// Collects the soft body's nodes whose tree leaves overlap a volume.
struct NodeCollector : btDbvt::ICollide {
  explicit NodeCollector(const btSoftBody& sb) : first(&sb.m_nodes[0]) {}
  void Process(const btDbvtNode* leaf) override {
    nodes.push_back(static_cast<int>(static_cast<const btSoftBody::Node*>(leaf->data) - first));
  }
  const btSoftBody::Node* first;
  std::vector<int> nodes;
};

// The object's pose at the start of the step. Bullet has already moved dynamic bodies by their
// velocity (stage 3) and kinematic ones to their scripted end pose (saveKinematicState); both
// moved by exactly integrateTransform(start, v, omega, dt), which we invert.
btTransform startPose(const btCollisionObject& object, double dt) {
  const btRigidBody* body = btRigidBody::upcast(&object);
  // Kinematic first: a mass-0 body made kinematic (Bullet's own recipe) keeps CF_STATIC_OBJECT
  // too, yet Bullet has moved it to its end pose. Taking that pose as the start pose shifted the
  // plate by one step's motion: nodes lagged a step behind a pressing plate and, when it stopped,
  // were taken as separating and dropped (docs/contact.md, the kinematic press).
  if (body == nullptr || (!body->isKinematicObject() && body->isStaticObject()))
    return object.getWorldTransform();
  btTransform start;
  btTransformUtil::integrateTransform(object.getWorldTransform(), -body->getLinearVelocity(),
                                      -body->getAngularVelocity(), toBtScalar(dt), start);
  return start;
}

// Whether Bullet's contact manifolds hold `body` against a static or kinematic object.
bool touchesStaticOrKinematic(const btRigidBody& body, btSoftBody& soft) {
  btDispatcher* dispatcher = soft.getWorldInfo()->m_dispatcher;
  if (dispatcher == nullptr) return false;
  for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
    const btCollisionObject* other = nullptr;
    if (manifold->getBody0() == &body) other = manifold->getBody1();
    if (manifold->getBody1() == &body) other = manifold->getBody0();
    if (other == nullptr || !other->isStaticOrKinematicObject()) continue;
    for (int c = 0; c < manifold->getNumContacts(); ++c) {
      if (manifold->getContactPoint(c).getDistance() <= manifold->getContactProcessingThreshold())
        return true;
    }
  }
  return false;
}

}  // namespace

btTransform RigidContactSolver::startPoseOf(const btCollisionObject& object) const {
  if (std::optional<btTransform> pose = links_.startPose(object)) return *pose;
  return startPose(object, dt_);
}

RigidContactSolver::RigidContactSolver(std::shared_ptr<const FemModel> model, btSoftBody* soft_body)
    : model_(std::move(model)), soft_body_(soft_body), faces_(model_->mesh()) {
  const int n = model_->nodeCount();
  surface_.assign(static_cast<size_t>(n), 0);
  for (const Triangle& tri : model_->mesh().surfaceTriangles()) {
    for (int a = 0; a < 3; ++a)
      surface_[static_cast<size_t>(tri[static_cast<size_t>(a)])] = 1;
  }
  node_contact_.assign(static_cast<size_t>(n), -1);
}

void RigidContactSolver::beginStep(double /*dt*/) {
  candidates_.clear();
  links_.beginStep();
  recordAnchorStartPoses();
}

void RigidContactSolver::addCandidate(const btCollisionObject* object) {
  // A concave object reaches us once per overlapping triangle: keep it once.
  if (std::find(candidates_.begin(), candidates_.end(), object) == candidates_.end())
    candidates_.push_back(object);
  links_.recordStartPose(object);
}

int RigidContactSolver::partnerIndex(const btCollisionObject* object) {
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (partners_[k].object == object) return static_cast<int>(k);
  }
  RigidPartner p;
  p.object = object;
  p.body = const_cast<btRigidBody*>(btRigidBody::upcast(object));
  if (p.body != nullptr) {
    p.entry_velocity << toEigen(p.body->getLinearVelocity()), toEigen(p.body->getAngularVelocity());
    p.dynamic = !p.body->isStaticOrKinematicObject() && p.body->getInvMass() > 0;
  }
  p.com = toEigen(startPoseOf(*object).getOrigin());
  links_.describe(object, p);
  if (p.dynamic && p.body != nullptr) {
    p.mass = 1.0 / toDouble(p.body->getInvMass());
    p.inverse_inertia = toEigen(p.body->getInvInertiaTensorWorld());
    // A zero inverse inertia component (locked rotation) has no inverse: keep it rigid.
    Eigen::Matrix3d regular = p.inverse_inertia;
    regular.diagonal().array() += 1e-12 * std::max(1.0, regular.norm());
    p.inertia = regular.inverse();
    p.mass_matrix.setZero();
    p.mass_matrix.topLeftCorner<3, 3>() = p.mass * Eigen::Matrix3d::Identity();
    p.mass_matrix.bottomRightCorner<3, 3>() = p.inertia;
    p.inverse_mass_matrix.setZero();
    p.inverse_mass_matrix.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() / p.mass;
    p.inverse_mass_matrix.bottomRightCorner<3, 3>() = p.inverse_inertia;
    if (touchesStaticOrKinematic(*p.body, *soft_body_)) {
      p.dynamic = false;
      p.supported = true;
    }
  }
  p.velocity = p.entry_velocity;
  partners_.push_back(p);
  return static_cast<int>(partners_.size()) - 1;
}

void RigidContactSolver::chooseSupportPlane(const btCollisionShape& shape,
                                            const btTransform& transform, const Eigen::Vector3d& x,
                                            const Eigen::Vector3d& node_velocity,
                                            const Eigen::Vector3d& into_surface, double dt,
                                            NodeContact& c) const {
  // The contact is linearised on one supporting plane of the (convex) rigid shape: the node must
  // end the step outside it. The nearest feature's plane is exact at the start of the step but
  // not over it: a node on a flat surface just ahead of a sliding box sees the box's front face
  // (a horizontal normal), and the linearised end gap along it, d - v dt, stops the box at the
  // node as at a wall, although the box's bottom edge would pass over it (docs/contact.md,
  // "Sliding over nodes"). The supporting plane facing the soft surface (normal minus the node's
  // surface normal: the bottom face's plane for a box on a slab) is as valid a bound. Of the two,
  // the one the predicted motion (the node's velocity, the rigid body's velocity after Bullet's
  // integration) leaves the larger end gap is taken. At rest they agree or the nearest wins: a
  // supporting plane never measures more than the distance.
  const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
  if (into_surface.squaredNorm() == 0) return;
  const std::optional<SurfacePoint> plane = supportPlaneDistance(shape, transform, x, into_surface);
  if (!plane) return;
  // Where the node would touch the plane: its foot on the plane, moved onto the shape.
  const Eigen::Vector3d foot = x - plane->distance * plane->normal;
  const std::optional<SurfacePoint> onto = signedDistance(shape, transform, foot, 0);
  const Eigen::Vector3d contact_point =
      onto ? Eigen::Vector3d(foot - onto->distance * onto->normal) : foot;
  const Eigen::Vector3d lever = contact_point - k.com;
  // Only the motion along the plane predicts which side the node ends on: across it, the rigid
  // body's predicted velocity carries the step's gravity, which the contacts under it cancel.
  Eigen::Vector3d slip = node_velocity - pointVelocity(k.entry_velocity, c.lever);
  slip -= plane->normal * plane->normal.dot(slip);
  const double end_nearest = c.gap + dt * c.normal.dot(slip);
  const double end_plane = plane->distance;
  if (end_plane <= end_nearest + kPlaneChoiceMargin) return;
  c.normal = plane->normal;
  c.gap = plane->distance;
  c.lever = lever;
  c.swept = true;
}

bool RigidContactSolver::detect(const FemState& state, const NodeConstraints& constraints,
                                double dt) {
  // Remember last step's active contacts: they start this step active (warm active set).
  previous_active_.clear();
  previous_state_.clear();
  for (const NodeContact& c : contacts_) {
    if (c.state != NodeContact::State::kInactive && !c.held) {
      previous_active_.emplace_back(c.node, partners_[static_cast<size_t>(c.partner)].object);
      previous_state_.push_back(c.state);
    }
  }
  for (const NodeContact& c : contacts_) {
    if (c.node >= 0 && !c.held) node_contact_[static_cast<size_t>(c.node)] = -1;
  }
  faces_.beginStep(partners_);
  contacts_.clear();
  partners_.clear();
  stats_ = ContactStepStats{};
  dt_ = dt;
  dynamic_count_ = 0;
  if (candidates_.empty() && anchors_.empty()) return false;

  const btSoftBody& sb = *soft_body_;
  const double margin = sb.getCollisionShape()->getMargin();
  double max_node_speed = 0;
  for (int i = 0; i < model_->nodeCount(); ++i)
    max_node_speed = std::max(max_node_speed, state.velocity(i).norm());

  // A triangle that overlaps an object's box has its nodes within the longest edge of it.
  const double longest_edge = faces_.longestEdge(state);
  for (const btCollisionObject* object : candidates_) {
    const btCollisionShape* shape = object->getCollisionShape();
    const btTransform transform = startPoseOf(*object);
    const btRigidBody* body = btRigidBody::upcast(object);
    double rigid_speed = 0;
    btVector3 lo, hi;
    shape->getAabb(transform, lo, hi);
    if (body != nullptr) {
      const double radius = 0.5 * toDouble((hi - lo).length());
      rigid_speed = toDouble(body->getLinearVelocity().length()) +
                    toDouble(body->getAngularVelocity().length()) * std::min(radius, 1e6);
    } else {
      rigid_speed = MultibodyLinks::speedBound(*object, 0.5 * toDouble((hi - lo).length()));
    }
    // Anything that can close the gap within the step, twice over, plus the soft margin.
    const double reach = 2 * dt * (max_node_speed + rigid_speed) + 4 * margin;
    const btVector3 pad = toBt(Eigen::Vector3d::Constant(reach));
    const btVector3 face_pad = pad + toBt(Eigen::Vector3d::Constant(longest_edge));
    NodeCollector collector(sb);
    sb.m_ndbvt.collideTV(sb.m_ndbvt.m_root, btDbvtVolume::FromMM(lo - face_pad, hi + face_pad),
                         collector);
    const Eigen::Vector3d node_lo = toEigen(lo - pad), node_hi = toEigen(hi + pad);
    for (int i : collector.nodes) {
      if (!surface_[static_cast<size_t>(i)]) continue;
      if (anchors_.anchored(i) && constraints.kind(i) != NodeConstraints::Kind::kFull) continue;
      const Eigen::Vector3d x = state.position(i);
      if ((x.array() < node_lo.array()).any() || (x.array() > node_hi.array()).any()) continue;
      std::optional<SurfacePoint> sp =
          signedDistance(*shape, transform, x, reach, -toEigen(sb.m_nodes[i].m_n));
      if (!sp) continue;
      const bool held = constraints.kind(i) == NodeConstraints::Kind::kFull;
      // Every node within reach is a candidate, separating or not: the active set decides.
      // Filtering by the start-of-step closing speed dropped nodes of a compressed body that were
      // moving away but sprang back within the implicit step (the kinematic press).
      NodeContact c;
      c.node = i;
      c.partner = partnerIndex(object);
      c.normal = sp->normal;
      c.gap = sp->distance;
      c.distance = sp->distance;
      c.lever = x - sp->distance * sp->normal - partners_[static_cast<size_t>(c.partner)].com;
      c.friction = settings_.friction * toDouble(object->getFriction());
      c.held = held;
      chooseSupportPlane(*shape, transform, x, state.velocity(i), -toEigen(sb.m_nodes[i].m_n), dt,
                         c);
      // One contact per free node: the deepest.
      if (!held) {
        int& slot = node_contact_[static_cast<size_t>(i)];
        if (slot >= 0) {
          if (contacts_[static_cast<size_t>(slot)].distance <= c.distance) continue;
          contacts_[static_cast<size_t>(slot)] = c;
          continue;
        }
        slot = static_cast<int>(contacts_.size());
      }
      contacts_.push_back(c);
    }
    const int partner = partnerIndex(object);
    faces_.detect(state, constraints, collector.nodes, *shape, transform, toEigen(lo), toEigen(hi),
                  reach, dt, partner, partners_[static_cast<size_t>(partner)],
                  settings_.friction * toDouble(object->getFriction()));
  }
  addAnchorContacts(state, constraints);
  // A candidate object that nothing touches keeps Bullet's velocity untouched: not an unknown.
  std::vector<char> touched(partners_.size(), 0);
  for (const NodeContact& c : contacts_)
    touched[static_cast<size_t>(c.partner)] = 1;
  for (const FaceContact& c : faces_.contacts())
    touched[static_cast<size_t>(c.partner)] = 1;
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (!touched[k]) partners_[k].dynamic = partners_[k].supported = false;
  }
  // Warm active set.
  std::vector<char> slid(partners_.size(), 0), stuck(partners_.size(), 0);
  for (NodeContact& c : contacts_) {
    if (c.held || c.anchored) continue;
    for (size_t k = 0; k < previous_active_.size(); ++k) {
      if (previous_active_[k].first == c.node &&
          previous_active_[k].second == partners_[static_cast<size_t>(c.partner)].object) {
        c.state = c.friction > 0 ? previous_state_[k] : NodeContact::State::kSlide;
        if (c.friction > 0 && c.state == NodeContact::State::kSlide)
          slid[static_cast<size_t>(c.partner)] = 1;
        if (c.state == NodeContact::State::kStick) stuck[static_cast<size_t>(c.partner)] = 1;
      }
    }
  }
  for (size_t k = 0; k < partners_.size(); ++k)
    partners_[k].sliding = slid[k] && !stuck[k];
  stats_.candidates = static_cast<int>(contacts_.size());
  stats_.face_candidates = static_cast<int>(faces_.contacts().size());
  for (const NodeContact& c : contacts_) {
    if (!c.anchored) stats_.max_penetration = std::max(stats_.max_penetration, -c.distance);
  }
  for (const FaceContact& c : faces_.contacts())
    stats_.max_penetration = std::max(stats_.max_penetration, -c.gap);
  return !contacts_.empty() || !faces_.empty();
}

// ---- the reduced system -------------------------------------------------------------------
// Unknowns q = (u, V): u (3n) the free node velocity components, V (6 per dynamic partner) the
// rigid velocities. Node velocities are v = T q + v_c:
//   free node              v_i = u_i
//   held node              v_i = S_i u_i (= 0 for a fully prescribed node)      + prescribed
//   sliding on partner k   v_i = P_n u_i + n n.(J_i V_k)  (the second term if k is dynamic)
//   sticking on partner k  v_i = J_i V_k                   (if k is dynamic)
// with v_c holding the prescribed parts (node groups, the gap closure -gap/dt along n, a static
// or kinematic partner's surface velocity). The reduced operator is T^T A T + diag(M_k), the
// reduced right-hand side T^T (b - A v_c) + M_k V_k(Bullet) - sum J^T f (sliding friction).

void RigidContactSolver::expand(const Eigen::VectorXd& q, Eigen::VectorXd& v) const {
  const int n = model_->nodeCount();
  v.resize(3 * n);
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    Eigen::Vector3d u = q.segment<3>(3 * i);
    if (base_->isConstrained(i)) {
      v.segment<3>(3 * i) = base_->filterNode(i, u);
      continue;
    }
    if (ci < 0 || contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kInactive) {
      v.segment<3>(3 * i) = u;
      continue;
    }
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d& nrm = c.normal;
    Eigen::Vector3d vi = Eigen::Vector3d::Zero();
    Eigen::Vector3d rigid = Eigen::Vector3d::Zero();
    if (k.dynamic) rigid = pointVelocity(q.segment<6>(k.unknown), c.lever);
    if (c.state == NodeContact::State::kSlide) {
      vi = u - nrm * nrm.dot(u) + nrm * nrm.dot(rigid);
    } else {
      vi = rigid;
    }
    v.segment<3>(3 * i) = vi;
  }
}

void RigidContactSolver::contract(const Eigen::VectorXd& y, const Eigen::VectorXd& rigid_part,
                                  Eigen::VectorXd& q) const {
  const int n = model_->nodeCount();
  q.resize(3 * n + 6 * dynamic_count_);
  q.tail(6 * dynamic_count_) = rigid_part;
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    const Eigen::Vector3d yi = y.segment<3>(3 * i);
    if (base_->isConstrained(i)) {
      q.segment<3>(3 * i) = base_->filterNode(i, yi);
      continue;
    }
    if (ci < 0 || contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kInactive) {
      q.segment<3>(3 * i) = yi;
      continue;
    }
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d& nrm = c.normal;
    if (c.state == NodeContact::State::kSlide) {
      q.segment<3>(3 * i) = yi - nrm * nrm.dot(yi);
      if (k.dynamic) q.segment<6>(k.unknown) += pointWrench(nrm * nrm.dot(yi), c.lever);
    } else {
      q.segment<3>(3 * i).setZero();
      if (k.dynamic) q.segment<6>(k.unknown) += pointWrench(yi, c.lever);
    }
  }
}

void RigidContactSolver::applyOperator(const SystemOperator& op, const Eigen::VectorXd& q,
                                       Eigen::VectorXd& out) {
  expand(q, scratch_);
  op.multiply(scratch_, product_);
  rigid_scratch_.resize(6 * dynamic_count_);
  for (const RigidPartner& k : partners_) {
    if (!k.dynamic) continue;
    const int o = k.unknown - 3 * model_->nodeCount();
    rigid_scratch_.segment<6>(o) = partnerMomentum(k, q.segment<6>(k.unknown));
  }
  faces_.addProduct(scratch_, q, partners_, 3 * model_->nodeCount(), product_, rigid_scratch_);
  contract(product_, rigid_scratch_, out);
}

void RigidContactSolver::buildPreconditioner(const SystemOperator& op) {
  const int n = model_->nodeCount();
  op.diagonalBlocks(block_inverse_);
  rigid_inverse_.assign(partners_.size(), Eigen::Matrix<double, 6, 6>::Zero());
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (!partners_[k].dynamic) continue;
    rigid_inverse_[k] = partners_[k].mass_matrix;
  }
  faces_.addPreconditioner(block_inverse_, rigid_inverse_, partners_);
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    if (ci < 0 || base_->isConstrained(i)) continue;
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    if (c.state == NodeContact::State::kInactive ||
        !partners_[static_cast<size_t>(c.partner)].dynamic)
      continue;
    // G_i^T D_i G_i with G_i = n n^T J_i (slide) or J_i (stick).
    Eigen::Matrix<double, 3, 6> J;
    J << Eigen::Matrix3d::Identity(), -(Eigen::Matrix3d() << 0, -c.lever.z(), c.lever.y(),
                                        c.lever.z(), 0, -c.lever.x(), -c.lever.y(), c.lever.x(), 0)
                                           .finished();
    Eigen::Matrix<double, 3, 6> G = J;
    if (c.state == NodeContact::State::kSlide) G = c.normal * (c.normal.transpose() * J);
    rigid_inverse_[static_cast<size_t>(c.partner)] +=
        G.transpose() * block_inverse_[static_cast<size_t>(i)] * G;
  }
  for (auto& block : block_inverse_)
    block = block.inverse().eval();
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (partners_[k].dynamic) rigid_inverse_[k] = rigid_inverse_[k].inverse().eval();
  }
}

void RigidContactSolver::precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  const int n = model_->nodeCount();
  z.resize(r.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d zi = block_inverse_[static_cast<size_t>(i)] * r.segment<3>(3 * i);
    const int ci = node_contact_[static_cast<size_t>(i)];
    if (base_->isConstrained(i)) {
      z.segment<3>(3 * i) = base_->filterNode(i, zi);
    } else if (ci < 0 ||
               contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kInactive) {
      z.segment<3>(3 * i) = zi;
    } else if (contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kSlide) {
      const Eigen::Vector3d& nrm = contacts_[static_cast<size_t>(ci)].normal;
      z.segment<3>(3 * i) = zi - nrm * nrm.dot(zi);
    } else {
      z.segment<3>(3 * i).setZero();
    }
  }
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (!partners_[k].dynamic) continue;
    const int o = partners_[k].unknown;
    z.segment<6>(o) = rigid_inverse_[k] * r.segment<6>(o);
  }
}

LinearSolveReport RigidContactSolver::conjugateGradient(const SystemOperator& op,
                                                        const Eigen::VectorXd& reduced_rhs,
                                                        const SolverSettings& settings,
                                                        Eigen::VectorXd& q) {
  applyOperator(op, q, cg_.q);
  r_ = reduced_rhs - cg_.q;
  return pcgIterations(
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) { applyOperator(op, in, out); },
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) { precondition(in, out); },
      reduced_rhs.norm(), settings, q, r_, cg_);
}

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
        if (gap_end < -settings_.activation_tolerance) {
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
          Eigen::Vector3d slip = vi - rigid_v;
          slip -= c.normal * c.normal.dot(slip);
          const double slipped = dt * slip.norm();
          const bool slipping = (c.swept && slipped > settings_.activation_tolerance) ||
                                (k.sliding && slipped > std::max(settings_.activation_tolerance,
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
        if (lambda < -noise && c.releases == 0) {
          c.state = NodeContact::State::kInactive;
          ++c.releases;
          changed = true;
        } else if (pt.norm() > k.friction_share * c.friction * std::max(lambda, 0.0) + noise &&
                   c.slips < kMaxSlipsPerStep) {
          // Anti-cycling, as for releases: in a body pressed between two surfaces the nodes'
          // tangential and normal impulses are coupled through the body, and per-node stick/slide
          // switching can cycle. After kMaxSlipsPerStep slips in a step a contact stays stuck for
          // the rest of the step (its friction may then exceed mu lambda for that step; it is
          // re-examined from the next step on). Letting it slide instead (sticking bounded)
          // let a block below the friction angle creep 12 mm in 1 s.
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
        if (lambda < -noise && c.releases == 0) {
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

LinearSolveReport RigidContactSolver::solve(const SystemOperator& op,
                                            const NodeConstraints& constraints,
                                            const Eigen::VectorXd& b,
                                            const SolverSettings& settings, Eigen::VectorXd& v) {
  base_ = &constraints;
  const int n = model_->nodeCount();
  const double dt = dt_;
  dynamic_count_ = 0;
  for (RigidPartner& k : partners_) {
    if (!k.dynamic) continue;
    k.unknown = 3 * n + 6 * dynamic_count_++;
  }
  for (RigidPartner& k : partners_)
    k.velocity = k.entry_velocity;

  LinearSolveReport total;
  Eigen::VectorXd b_friction;
  Eigen::VectorXd rigid_rhs(6 * dynamic_count_);
  // Warm start: the given node velocities, Bullet's rigid velocities.
  q_.resize(3 * n + 6 * dynamic_count_);
  q_.head(3 * n) = v;
  for (const RigidPartner& k : partners_) {
    if (k.dynamic) q_.segment<6>(k.unknown) = k.entry_velocity;
  }
  if (!faces_.empty()) {
    op.diagonalBlocks(block_inverse_);
    faces_.setPenalties(block_inverse_, settings_.face_penalty);
  }
  bool converged_set = false;
  for (int iteration = 0; iteration < settings_.max_active_set_iterations; ++iteration) {
    // Face contacts whose nodes are all prescribed along their normal sit this solve out.
    faces_.markDetermined([&](int node, const Eigen::Vector3d& normal) {
      if (constraints.kind(node) == NodeConstraints::Kind::kFull) return true;
      const int ci = node_contact_[static_cast<size_t>(node)];
      if (ci < 0) return false;
      const NodeContact& c = contacts_[static_cast<size_t>(ci)];
      return c.state == NodeContact::State::kStick ||
             (c.state == NodeContact::State::kSlide && std::abs(c.normal.dot(normal)) > 0.99);
    });
    // Prescribed parts v_c and the friction impulses.
    v_c_.setZero(3 * n);
    constraints.impose(v_c_);
    b_friction = b;
    for (const RigidPartner& k : partners_) {
      if (!k.dynamic) continue;
      const int o = k.unknown - 3 * n;
      rigid_rhs.segment<6>(o) = partnerMomentum(k, k.entry_velocity);
    }
    for (const NodeContact& c : contacts_) {
      if (c.held || c.state == NodeContact::State::kInactive) continue;
      const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
      // End gap gap + dt n.(v_i - J_i V) = 0: the node closes the gap relative to the rigid
      // surface, whose velocity is an unknown (dynamic) or given (static, kinematic).
      Eigen::Vector3d vc = c.normal * (-c.gap / dt);
      if (!k.dynamic) {
        const Eigen::Vector3d rigid = pointVelocity(k.entry_velocity, c.lever);
        vc += c.state == NodeContact::State::kStick
                  ? rigid
                  : Eigen::Vector3d(c.normal * c.normal.dot(rigid));
      }
      v_c_.segment<3>(3 * c.node) = vc;
      if (c.state == NodeContact::State::kSlide) {
        b_friction.segment<3>(3 * c.node) += c.friction_impulse;
        if (k.dynamic)
          rigid_rhs.segment<6>(k.unknown - 3 * n) -= pointWrench(c.friction_impulse, c.lever);
      }
    }
    b_solve_ = b_friction;
    faces_.addRightHandSide(v_c_, partners_, dt, 3 * n, b_solve_, rigid_rhs);
    op.multiply(v_c_, product_);
    contract(b_solve_ - product_, rigid_rhs, reduced_rhs_);

    // Keep the warm start inside the reduced space (the rigid part is kept as is).
    {
      Eigen::VectorXd u = q_.head(3 * n);
      for (int i = 0; i < n; ++i) {
        const int ci = node_contact_[static_cast<size_t>(i)];
        Eigen::Vector3d ui = u.segment<3>(3 * i);
        if (constraints.isConstrained(i)) {
          ui = constraints.filterNode(i, ui);
        } else if (ci >= 0) {
          const NodeContact& c = contacts_[static_cast<size_t>(ci)];
          if (c.state == NodeContact::State::kSlide) ui -= c.normal * c.normal.dot(ui);
          if (c.state == NodeContact::State::kStick) ui.setZero();
        }
        q_.segment<3>(3 * i) = ui;
      }
    }
    buildPreconditioner(op);
    const LinearSolveReport r = conjugateGradient(op, reduced_rhs_, settings, q_);
    total.iterations += r.iterations;
    total.relative_residual = r.relative_residual;
    total.converged = r.converged;
    total.breakdown = total.breakdown || r.breakdown;
    if (r.breakdown_reason != nullptr) total.breakdown_reason = r.breakdown_reason;
    ++stats_.active_set_iterations;

    expand(q_, v);
    v += v_c_;
    for (RigidPartner& k : partners_) {
      if (k.dynamic) k.velocity = q_.segment<6>(k.unknown);
    }
    // Constraint impulses on the nodes: A v - b less the friction and the face contacts'
    // impulses (neither is a node's constraint impulse).
    op.multiply(v, product_);
    product_ -= b_friction;
    faces_.takeImpulses(v, partners_, dt, product_);
    if (r.breakdown) break;
    measureFrictionShares();
    const bool nodes_changed = updateActiveSet(v, product_, dt);
    const bool faces_changed = faces_.update(v, partners_, dt, settings_.activation_tolerance,
                                             settings_.face_gap_tolerance);
    if (!nodes_changed && !faces_changed) {
      converged_set = true;
      break;
    }
  }
  stats_.active_set_converged = converged_set;

  // Impulses, statistics, and what the rigid bodies receive.
  for (NodeContact& c : contacts_) {
    if (c.held) continue;
    if (c.state == NodeContact::State::kInactive) {
      c.impulse.setZero();
      c.normal_impulse = 0;
      continue;
    }
    const Eigen::Vector3d pi = product_.segment<3>(3 * c.node);
    c.impulse =
        (c.state == NodeContact::State::kStick ? pi
                                               : Eigen::Vector3d(c.normal * c.normal.dot(pi))) +
        (c.state == NodeContact::State::kSlide ? c.friction_impulse : Eigen::Vector3d::Zero());
    c.normal_impulse = c.normal.dot(c.impulse);
    RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    k.impulse -= pointWrench(c.impulse, c.lever);
    ++stats_.active;
    if (c.state == NodeContact::State::kStick) ++stats_.sticking;
    stats_.normal_impulse += std::max(0.0, c.normal_impulse);
  }
  for (const FaceContact& c : faces_.contacts()) {
    if (c.state == FaceContact::State::kInactive || c.determined) continue;
    partners_[static_cast<size_t>(c.partner)].impulse -= pointWrench(c.impulse, c.lever);
    ++stats_.active;
    ++stats_.face_active;
    stats_.normal_impulse += std::max(0.0, c.normal.dot(c.impulse));
  }
  solveHeld(v, dt);
  // The linearised end-of-step gap of every contact, with the final velocities.
  for (const NodeContact& c : contacts_) {
    const Eigen::Vector3d rigid =
        pointVelocity(partners_[static_cast<size_t>(c.partner)].velocity, c.lever);
    const double gap_end = c.gap + dt * c.normal.dot(v.segment<3>(3 * c.node) - rigid);
    stats_.max_end_penetration = std::max(stats_.max_end_penetration, -gap_end);
  }
  for (const FaceContact& c : faces_.contacts()) {
    stats_.max_end_penetration =
        std::max(stats_.max_end_penetration, -faces_.endGap(c, v, partners_, dt));
  }
  return total;
}

void RigidContactSolver::solveHeld(const Eigen::VectorXd& v, double dt) {
  // Held nodes are kinematic: each pushes its dynamic partner away (projected Gauss-Seidel on
  // the rigid body alone, normal impulse >= 0, Coulomb friction), never the other way round.
  std::vector<int> held;
  for (size_t c = 0; c < contacts_.size(); ++c) {
    const RigidPartner& k = partners_[static_cast<size_t>(contacts_[c].partner)];
    if (contacts_[c].held && (k.dynamic || k.supported)) held.push_back(static_cast<int>(c));
  }
  if (held.empty()) return;
  std::vector<Eigen::Vector3d> accumulated(held.size(), Eigen::Vector3d::Zero());
  for (int sweep = 0; sweep < settings_.held_iterations; ++sweep) {
    for (size_t h = 0; h < held.size(); ++h) {
      NodeContact& c = contacts_[static_cast<size_t>(held[h])];
      RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
      const Eigen::Vector3d w = v.segment<3>(3 * c.node);
      auto response = [&](const Eigen::Vector3d& dir) {
        // dir . W dir: the rigid point's speed change along dir per unit impulse along dir.
        return dir.dot(pointVelocity(partnerResponse(k, pointWrench(dir, c.lever)), c.lever));
      };
      // Normal: n . J V <= n . w + gap/dt, i.e. the end gap >= 0.
      const double bound = c.normal.dot(w) + c.gap / dt;
      const double violation = c.normal.dot(pointVelocity(k.velocity, c.lever)) - bound;
      double& lambda = accumulated[h].x();
      const double lambda_new = std::max(0.0, lambda + violation / response(c.normal));
      const double d_lambda = lambda_new - lambda;
      lambda = lambda_new;
      const Eigen::Vector3d impulse_on_rigid = -c.normal * d_lambda;
      k.velocity += partnerResponse(k, pointWrench(impulse_on_rigid, c.lever));
      k.impulse += pointWrench(impulse_on_rigid, c.lever);
      c.impulse -= impulse_on_rigid;
      // Friction: remove the tangential slip within mu lambda.
      Eigen::Vector3d slip = pointVelocity(k.velocity, c.lever) - w;
      slip -= c.normal * c.normal.dot(slip);
      const double s = slip.norm();
      if (s > 0 && c.friction > 0) {
        const Eigen::Vector3d t = slip / s;
        Eigen::Vector3d tangential = c.impulse - c.normal * c.normal.dot(c.impulse);
        Eigen::Vector3d target = tangential + t * (s / response(t));  // on the node
        const double cap = c.friction * lambda;
        if (target.norm() > cap) target *= cap / target.norm();
        const Eigen::Vector3d change_on_rigid = -(target - tangential);
        k.velocity += partnerResponse(k, pointWrench(change_on_rigid, c.lever));
        k.impulse += pointWrench(change_on_rigid, c.lever);
        c.impulse -= change_on_rigid;
      }
      c.normal_impulse = c.normal.dot(c.impulse);
    }
  }
  for (size_t h = 0; h < held.size(); ++h) {
    const NodeContact& c = contacts_[static_cast<size_t>(held[h])];
    if (accumulated[h].x() > 0) {
      ++stats_.active;
      stats_.normal_impulse += std::max(0.0, c.normal_impulse);
    }
  }
}

void RigidContactSolver::finish() {
  links_.applyImpulses(partners_, dt_);
  for (RigidPartner& k : partners_) {
    if (k.link != nullptr) continue;
    if (k.supported && k.body != nullptr) {
      // Explicit: the impulse changes the velocity only; Bullet's rigid solver meets it next
      // step together with the body's other contacts (the ground), which alone it knows.
      k.body->applyCentralImpulse(toBt(k.impulse.head<3>()));
      k.body->applyTorqueImpulse(toBt(k.impulse.tail<3>()));
      k.body->activate();
      continue;
    }
    if (!k.dynamic || k.body == nullptr) continue;
    if (k.velocity == k.entry_velocity) continue;
    // Bullet integrated the pose with entry_velocity; the step's velocity is `velocity`
    // (symplectic Euler with the contact impulse inside the step).
    const Vector6d dV = k.velocity - k.entry_velocity;
    btTransform corrected;
    btTransformUtil::integrateTransform(k.body->getCenterOfMassTransform(), toBt(dV.head<3>()),
                                        toBt(dV.tail<3>()), toBtScalar(dt_), corrected);
    k.body->setLinearVelocity(toBt(k.velocity.head<3>()));
    k.body->setAngularVelocity(toBt(k.velocity.tail<3>()));
    k.body->setCenterOfMassTransform(corrected);
    if (k.body->getMotionState() != nullptr) k.body->getMotionState()->setWorldTransform(corrected);
    k.body->activate();
  }
}

}  // namespace torsion
