// Narrow phase of the FEM-rigid contact (docs/contact-pipeline.md, "Narrow phase"): the candidate
// objects of Bullet's broadphase against the body's node tree and surface triangles, each touched
// object made a partner of the solve, and the warm active set carried over from the last step.

#include <BulletCollision/BroadphaseCollision/btDbvt.h>
#include <BulletCollision/BroadphaseCollision/btDispatcher.h>
#include <BulletCollision/NarrowPhaseCollision/btPersistentManifold.h>
#include <LinearMath/btTransformUtil.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/shape_distance.h"

namespace torsion {

namespace {

// m: a supporting plane replaces the nearest feature's only if it leaves a larger predicted end
// gap by more than round-off (at rest the two agree).
constexpr double kDetectionPlaneMargin = 1e-9;
// m: how far beyond a face's edge a node's foot may fall and still be over the face (the stated
// penetration tolerance of a rigid feature between nodes).
constexpr double kOverFaceTolerance = 1e-5;

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
  // were taken as separating and dropped (docs/contact-pipeline.md, the kinematic press).
  if (body == nullptr || (!body->isKinematicObject() && body->isStaticObject()))
    return object.getWorldTransform();
  btTransform start;
  btTransformUtil::integrateTransform(object.getWorldTransform(), -body->getLinearVelocity(),
                                      -body->getAngularVelocity(), toBtScalar(dt), start);
  return start;
}

// Whether Bullet's contact manifolds hold `body` up against a static or kinematic object: a
// contact whose push on the body opposes the body's gravity (within 60 deg; any contact when it
// has no gravity). A kinematic plate pushing a box sideways across a soft slab does not hold it
// up: taken as support, the box was prescribed in the solve with the step's gravity in its
// velocity, the slab's reaction (a hundred times its weight) came back as an explicit impulse,
// and the box was thrown off the slab.
bool touchesStaticOrKinematic(const btRigidBody& body, btSoftBody& soft) {
  btDispatcher* dispatcher = soft.getWorldInfo()->m_dispatcher;
  if (dispatcher == nullptr) return false;
  const Eigen::Vector3d gravity = toEigen(body.getGravity());
  const Eigen::Vector3d up =
      gravity.squaredNorm() > 0 ? Eigen::Vector3d(-gravity.normalized()) : Eigen::Vector3d::Zero();
  for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
    const btCollisionObject* other = nullptr;
    double side = 0;  // the push on the body is side * normalWorldOnB
    if (manifold->getBody0() == &body) {
      other = manifold->getBody1();
      side = 1;
    }
    if (manifold->getBody1() == &body) {
      other = manifold->getBody0();
      side = -1;
    }
    if (other == nullptr || !other->isStaticOrKinematicObject()) continue;
    for (int c = 0; c < manifold->getNumContacts(); ++c) {
      const btManifoldPoint& point = manifold->getContactPoint(c);
      if (point.getDistance() > manifold->getContactProcessingThreshold()) continue;
      const Eigen::Vector3d push = side * toEigen(point.m_normalWorldOnB);
      if (up.squaredNorm() == 0 || push.dot(up) > 0.5) return true;
    }
  }
  return false;
}

}  // namespace

std::vector<char> RigidContactSolver::gluedTo(const btCollisionObject& object) const {
  std::vector<char> glued;
  for (const NodeAnchor& anchor : anchors_.anchors()) {
    if (anchor.object != &object) continue;
    glued.resize(static_cast<size_t>(model_->nodeCount()), 0);
    for (int node : anchor.nodes)
      glued[static_cast<size_t>(node)] = 1;
  }
  return glued;
}

btTransform RigidContactSolver::startPoseOf(const btCollisionObject& object) const {
  if (std::optional<btTransform> pose = links_.startPose(object)) return *pose;
  return startPose(object, dt_);
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
    if (touchesStaticOrKinematic(*p.body, *soft_body_) && !islandTakesRigidContacts(*p.body)) {
      p.dynamic = false;
      p.supported = true;
    }
  }
  p.velocity = p.entry_velocity;
  partners_.push_back(p);
  return static_cast<int>(partners_.size()) - 1;
}

void RigidContactSolver::chooseSupportPlane(const btCollisionShape& shape,
                                            const btTransform& transform, const FemState& state,
                                            int node, const Eigen::Vector3d& into_surface,
                                            double dt, NodeContact& c) const {
  // The contact is linearised on one supporting plane of the (convex) rigid shape: the node must
  // end the step outside it. The nearest feature's plane is exact at the start of the step but
  // not over it: a node on a flat surface just ahead of a sliding box sees the box's front face
  // (a horizontal normal), and the linearised end gap along it, d - v dt, stops the box at the
  // node as at a wall, although the box's bottom edge would pass over it (docs/contact-pipeline.md,
  // "Sliding over nodes"). The supporting plane facing the soft surface (normal minus the node's
  // surface normal: the bottom face's plane for a box on a slab) is as valid a bound. Of these,
  // the one the predicted motion (the node's velocity, the rigid body's velocity after Bullet's
  // integration) leaves the largest end gap is taken. At rest they agree or the nearest wins: a
  // supporting plane never measures more than the distance.
  //
  // The convex solve also tries the plane facing each surface triangle at the node. At an edge
  // of the soft body the node's normal is the mean of its faces' (diagonal at a slab's end), and
  // the plane facing it is no better than the nearest: a box sliding off a slab's end met the end
  // nodes on its front face, as a wall, and was stopped and tipped over (SlabEdge.*). The plane
  // facing the slab's top lets the box's bottom pass over them.
  if (into_surface.squaredNorm() == 0) return;
  const Eigen::Vector3d x = state.position(node);
  const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
  const NodeContact nearest = c;
  const Eigen::Vector3d relative = state.velocity(node) - pointVelocity(k.entry_velocity, c.lever);
  bool taken = takeFacingPlane(shape, transform, x, into_surface, relative, dt, nearest, c);
  const std::vector<Triangle>& triangles = model_->mesh().surfaceTriangles();
  const auto [first, last] = faces_.trianglesOf(node);
  for (const int* t = first; t != last; ++t) {
    const Triangle& tri = triangles[static_cast<size_t>(*t)];
    const Eigen::Vector3d a = state.position(tri[0]);
    const Eigen::Vector3d normal = (state.position(tri[1]) - a).cross(state.position(tri[2]) - a);
    if (normal.squaredNorm() == 0) continue;
    taken = takeFacingPlane(shape, transform, x, -normal.normalized(), relative, dt, nearest, c) ||
            taken;
  }
  if (taken) c.swept = true;
}

bool RigidContactSolver::takeFacingPlane(const btCollisionShape& shape,
                                         const btTransform& transform, const Eigen::Vector3d& x,
                                         const Eigen::Vector3d& into,
                                         const Eigen::Vector3d& relative_velocity, double dt,
                                         const NodeContact& nearest, NodeContact& c) const {
  const std::optional<SurfacePoint> plane = supportPlaneDistance(shape, transform, x, into);
  if (!plane) return false;
  // Only the motion along the plane predicts which side the node ends on: across it, the rigid
  // body's predicted velocity carries the step's gravity, which the contacts under it cancel.
  Eigen::Vector3d slip = relative_velocity;
  slip -= plane->normal * plane->normal.dot(slip);
  const double end_nearest = nearest.gap + dt * nearest.normal.dot(slip);
  const double end_plane = plane->distance;
  if (end_plane <= end_nearest + kDetectionPlaneMargin) return false;
  // A plane already taken instead of the nearest: the one of larger end gap.
  if (c.normal != nearest.normal && end_plane <= c.gap + kDetectionPlaneMargin) return false;
  // Where the node would touch the plane: its foot on the plane, moved onto the shape.
  const Eigen::Vector3d foot = x - plane->distance * plane->normal;
  const std::optional<SurfacePoint> onto = signedDistance(shape, transform, foot, 0);
  const Eigen::Vector3d contact_point =
      onto ? Eigen::Vector3d(foot - onto->distance * onto->normal) : foot;
  c.normal = plane->normal;
  c.gap = plane->distance;
  c.lever = contact_point - partners_[static_cast<size_t>(c.partner)].com;
  return true;
}

void RigidContactSolver::keepPreviousPlane(const btCollisionShape& shape,
                                           const btTransform& transform, const Eigen::Vector3d& x,
                                           const Eigen::Vector3d& into_surface,
                                           const btCollisionObject& object, NodeContact& c) const {
  // A node that touched this object in the last step on a face that faces the soft surface keeps
  // that face's plane while it is still over it, against a nearest feature that faces the surface
  // less: the contact continues where it began. Chosen afresh, the nearest feature of a node on a
  // box's edge is a toss-up between the two faces that meet there: a soft block's top node under
  // the corner of a box that landed on it, 1 um into the bottom face and 0 um from a side face,
  // took the side face's horizontal normal, let go of the box, and the box sank through the
  // block. Only towards the face that faces the surface: a node ahead of a box sliding over a slab
  // must not keep the front face it saw as the nearest (chooseSupportPlane), or the box meets it
  // as a wall; nor is a plane the sweep chose (c.swept) replaced.
  if (c.swept) return;
  const int k = previous_of_node_.empty() ? -1 : previous_of_node_[static_cast<size_t>(c.node)];
  if (k < 0 || previous_active_[static_cast<size_t>(k)].second != &object) return;
  const Eigen::Vector3d& kept = previous_normal_[static_cast<size_t>(k)];
  if (kept.squaredNorm() == 0 || kept.dot(c.normal) > 0.99) return;
  if (kept.dot(into_surface) <= c.normal.dot(into_surface)) return;
  const std::optional<SurfacePoint> plane = supportPlaneDistance(shape, transform, x, kept);
  if (!plane) return;
  // Over the face: the node's foot on the plane lies on the shape, or beyond its edge by no more
  // than the stated penetration tolerance of a rigid feature (a corner node slips outward by
  // tenths of a micron as the block under a box bulges).
  const Eigen::Vector3d foot = x - plane->distance * plane->normal;
  const std::optional<SurfacePoint> onto = signedDistance(shape, transform, foot, 0);
  if (!onto || std::abs(onto->distance) > kOverFaceTolerance) return;
  c.normal = plane->normal;
  c.gap = plane->distance;
  c.lever = foot - partners_[static_cast<size_t>(c.partner)].com;
}

void RigidContactSolver::rememberActiveContacts() {
  // Last step's active contacts: their impulses are this step's friction bounds, their normals
  // the planes they keep (keepPreviousPlane).
  previous_active_.clear();
  previous_impulse_.clear();
  previous_normal_.clear();
  for (const NodeContact& c : contacts_) {
    if (c.state != NodeContact::State::kInactive && !c.held) {
      previous_active_.emplace_back(c.node, partners_[static_cast<size_t>(c.partner)].object);
      previous_impulse_.push_back(c.impulse);
      previous_normal_.push_back(c.normal);
    }
  }
  previous_of_node_.assign(static_cast<size_t>(model_->nodeCount()), -1);
  for (size_t k = 0; k < previous_active_.size(); ++k)
    previous_of_node_[static_cast<size_t>(previous_active_[k].first)] = static_cast<int>(k);
}

void RigidContactSolver::forgetLastStep(double dt) {
  for (const NodeContact& c : contacts_) {
    if (c.node >= 0 && !c.held) node_contact_[static_cast<size_t>(c.node)] = -1;
  }
  faces_.beginStep();
  contacts_.clear();
  partners_.clear();
  solved_faces_.clear();
  rigid_group_ = {};  // a failed step's (its finish() did not run)
  rigid_impulses_.clear();
  joint_impulses_.clear();
  stats_ = ContactStepStats{};
  dt_ = dt;
}

void RigidContactSolver::findContacts(const FemState& state, const NodeConstraints& constraints,
                                      double dt) {
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
      addNodeContact(state, constraints, *object, transform, i, reach, lookahead(dt));
    }
    const int partner = partnerIndex(object);
    faces_.detect(state, constraints, collector.nodes, *shape, transform, toEigen(lo), toEigen(hi),
                  reach, lookahead(dt), partner, partners_[static_cast<size_t>(partner)],
                  settings_.friction * toDouble(object->getFriction()), gluedTo(*object));
  }
}

void RigidContactSolver::addNodeContact(const FemState& state, const NodeConstraints& constraints,
                                        const btCollisionObject& object,
                                        const btTransform& transform, int i, double reach,
                                        double lookahead_time) {
  const btSoftBody& sb = *soft_body_;
  const btCollisionShape& shape = *object.getCollisionShape();
  const Eigen::Vector3d x = state.position(i);
  std::optional<SurfacePoint> sp =
      signedDistance(shape, transform, x, reach, -toEigen(sb.m_nodes[i].m_n));
  if (!sp) return;
  const bool held = constraints.kind(i) == NodeConstraints::Kind::kFull;
  // Every node within reach is a candidate, separating or not: the active set decides.
  // Filtering by the start-of-step closing speed dropped nodes of a compressed body that were
  // moving away but sprang back within the implicit step (the kinematic press).
  NodeContact c;
  c.node = i;
  c.partner = partnerIndex(&object);
  c.normal = sp->normal;
  c.gap = sp->distance;
  c.distance = sp->distance;
  c.lever = x - sp->distance * sp->normal - partners_[static_cast<size_t>(c.partner)].com;
  c.friction = settings_.friction * toDouble(object.getFriction());
  c.held = held;
  chooseSupportPlane(shape, transform, state, i, -toEigen(sb.m_nodes[i].m_n), lookahead_time, c);
  keepPreviousPlane(shape, transform, x, -toEigen(sb.m_nodes[i].m_n), object, c);
  // One contact per free node: the deepest.
  if (!held) {
    int& slot = node_contact_[static_cast<size_t>(i)];
    if (slot >= 0) {
      if (contacts_[static_cast<size_t>(slot)].distance <= c.distance) return;
      contacts_[static_cast<size_t>(slot)] = c;
      return;
    }
    slot = static_cast<int>(contacts_.size());
  }
  contacts_.push_back(c);
}

void RigidContactSolver::dropUntouchedPartners() {
  // A candidate object that nothing touches keeps Bullet's velocity untouched: not an unknown.
  std::vector<char> touched(partners_.size(), 0);
  for (const NodeContact& c : contacts_)
    touched[static_cast<size_t>(c.partner)] = 1;
  for (const FaceContact& c : faces_.contacts())
    touched[static_cast<size_t>(c.partner)] = 1;
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (!touched[k]) partners_[k].dynamic = partners_[k].supported = false;
  }
}

void RigidContactSolver::recordDetectionStats() {
  stats_.candidates = static_cast<int>(contacts_.size());
  stats_.face_candidates = static_cast<int>(faces_.contacts().size());
  for (const NodeContact& c : contacts_) {
    if (!c.anchored) stats_.max_penetration = std::max(stats_.max_penetration, -c.distance);
  }
  for (const FaceContact& c : faces_.contacts())
    stats_.max_penetration = std::max(stats_.max_penetration, -c.gap);
}

}  // namespace torsion
