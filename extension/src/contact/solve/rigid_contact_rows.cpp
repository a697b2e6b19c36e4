#include "torsion/contact/solve/rigid_contact_rows.h"

#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include <algorithm>
#include <cstddef>
#include <map>

#include "torsion/bt_conversions.h"
#include "torsion/contact/solve/node_contact_rows.h"

namespace torsion::sap {

namespace {

// A body whose response Bullet's solver computes as the FEM's does: neither asleep nor scaled by
// linear or angular factors. Empty when it is, else why not.
std::string whyBulletKeeps(const btRigidBody& body) {
  if (body.getActivationState() == ISLAND_SLEEPING) return "asleep";
  const btVector3 one(1, 1, 1);
  if (body.getLinearFactor() != one || body.getAngularFactor() != one)
    return "its linear or angular factor is not 1";
  return {};
}

btRigidBody* dynamicBody(const btCollisionObject* object) {
  const btRigidBody* body = btRigidBody::upcast(object);
  if (body == nullptr || body->isStaticOrKinematicObject() || body->getInvMass() <= 0)
    return nullptr;
  return const_cast<btRigidBody*>(body);
}

// The manifolds Bullet's solver used, with their points it solved (solveConstraints: both objects
// respond, distance within the processing threshold).
struct UsedManifold {
  btPersistentManifold* manifold = nullptr;
  std::vector<int> points;
};

std::vector<UsedManifold> usedManifolds(btDispatcher& dispatcher) {
  std::vector<UsedManifold> used;
  for (int m = 0; m < dispatcher.getNumManifolds(); ++m) {
    btPersistentManifold* manifold = dispatcher.getManifoldByIndexInternal(m);
    if (!dispatcher.needsResponse(manifold->getBody0(), manifold->getBody1())) continue;
    UsedManifold u{manifold, {}};
    for (int c = 0; c < manifold->getNumContacts(); ++c) {
      if (manifold->getContactPoint(c).getDistance() <= manifold->getContactProcessingThreshold())
        u.points.push_back(c);
    }
    if (!u.points.empty()) used.push_back(std::move(u));
  }
  return used;
}

// The connected component of `seed` through dynamic bodies, by contact and by joint: its bodies
// (the seed first) and the manifolds touching them.
struct Component {
  std::vector<btRigidBody*> bodies;
  std::vector<const UsedManifold*> manifolds;
  std::string kept;  // why Bullet keeps it, empty when it can be taken
};

void addOnce(std::vector<btRigidBody*>& bodies, btRigidBody* body) {
  if (body != nullptr && std::find(bodies.begin(), bodies.end(), body) == bodies.end())
    bodies.push_back(body);
}

Component componentOf(btRigidBody* seed, const std::vector<UsedManifold>& used,
                      const std::vector<btTypedConstraint*>& joints) {
  Component c;
  c.bodies.push_back(seed);
  std::vector<char> taken(used.size(), 0);
  for (std::size_t next = 0; next < c.bodies.size(); ++next) {
    btRigidBody* body = c.bodies[next];
    if (c.kept.empty()) {
      const std::string why = whyBulletKeeps(*body);
      if (!why.empty()) c.kept = "a rigid body in contact stays with Bullet: " + why;
    }
    for (std::size_t m = 0; m < used.size(); ++m) {
      const btPersistentManifold& manifold = *used[m].manifold;
      if (taken[m] || (manifold.getBody0() != body && manifold.getBody1() != body)) continue;
      taken[m] = 1;
      c.manifolds.push_back(&used[m]);
      const btCollisionObject* other =
          manifold.getBody0() == body ? manifold.getBody1() : manifold.getBody0();
      if (btMultiBodyLinkCollider::upcast(other) != nullptr && c.kept.empty())
        c.kept = "a rigid body touching a multibody link stays with Bullet";
      for (int p : used[m].points) {
        const btManifoldPoint& point = manifold.getContactPoint(p);
        if ((point.m_combinedRollingFriction != 0 || point.m_combinedSpinningFriction != 0) &&
            c.kept.empty())
          c.kept = "a rigid contact with rolling or spinning friction stays with Bullet";
      }
      addOnce(c.bodies, dynamicBody(other));
    }
    for (btTypedConstraint* joint : joints) {
      if (&joint->getRigidBodyA() == body) addOnce(c.bodies, dynamicBody(&joint->getRigidBodyB()));
      if (&joint->getRigidBodyB() == body) addOnce(c.bodies, dynamicBody(&joint->getRigidBodyA()));
    }
  }
  return c;
}

// Per side of a point: the group's body, its lever and (prescribed) its point velocity.
void describeSide(const btCollisionObject* object, const btVector3& on_object,
                  const std::map<const btRigidBody*, int>& index, const StartPose& start_pose,
                  int& body, Eigen::Vector3d& lever, Eigen::Vector3d& velocity) {
  const btRigidBody* rigid = btRigidBody::upcast(object);
  const auto found = rigid != nullptr ? index.find(rigid) : index.end();
  body = found != index.end() ? found->second : -1;
  lever = toEigen(on_object) - toEigen(start_pose(*object).getOrigin());
  velocity.setZero();
  if (body < 0 && rigid != nullptr) {
    velocity = pointVelocity(
        (Vector6d() << toEigen(rigid->getLinearVelocity()), toEigen(rigid->getAngularVelocity()))
            .finished(),
        lever);
  }
}

}  // namespace

bool RigidContactGroup::contains(const btRigidBody* body) const {
  return std::find(bodies.begin(), bodies.end(), body) != bodies.end();
}

RigidContactGroup gatherRigidContactGroup(btDispatcher& dispatcher,
                                          const std::vector<btRigidBody*>& seeds,
                                          const StartPose& start_pose,
                                          const std::vector<btTypedConstraint*>& joints) {
  RigidContactGroup group;
  const std::vector<UsedManifold> used = usedManifolds(dispatcher);
  std::vector<const UsedManifold*> manifolds;
  std::vector<btRigidBody*> seen;
  for (btRigidBody* seed : seeds) {
    if (std::find(seen.begin(), seen.end(), seed) != seen.end()) continue;
    const Component c = componentOf(seed, used, joints);
    seen.insert(seen.end(), c.bodies.begin(), c.bodies.end());
    if (!c.kept.empty()) {
      group.kept_by_bullet.push_back(c.kept);
      continue;
    }
    group.bodies.insert(group.bodies.end(), c.bodies.begin(), c.bodies.end());
    manifolds.insert(manifolds.end(), c.manifolds.begin(), c.manifolds.end());
  }
  std::map<const btRigidBody*, int> index;
  for (std::size_t b = 0; b < group.bodies.size(); ++b)
    index[group.bodies[b]] = static_cast<int>(b);
  group.bullet_impulses.assign(group.bodies.size(), Vector6d::Zero());
  for (const UsedManifold* u : manifolds) {
    const btPersistentManifold& manifold = *u->manifold;
    for (int p : u->points) {
      btManifoldPoint& point = const_cast<btPersistentManifold&>(manifold).getContactPoint(p);
      RigidContactPoint rp;
      rp.point = &point;
      describeSide(manifold.getBody0(), point.getPositionWorldOnA(), index, start_pose, rp.body_a,
                   rp.lever_a, rp.velocity_a);
      describeSide(manifold.getBody1(), point.getPositionWorldOnB(), index, start_pose, rp.body_b,
                   rp.lever_b, rp.velocity_b);
      // Bullet's impulse on A: along +n and its friction directions; on B the opposite.
      const Eigen::Vector3d on_a =
          toEigen(point.m_normalWorldOnB) * toDouble(point.m_appliedImpulse) +
          toEigen(point.m_lateralFrictionDir1) * toDouble(point.m_appliedImpulseLateral1) +
          toEigen(point.m_lateralFrictionDir2) * toDouble(point.m_appliedImpulseLateral2);
      if (rp.body_a >= 0)
        group.bullet_impulses[static_cast<std::size_t>(rp.body_a)] += pointWrench(on_a, rp.lever_a);
      if (rp.body_b >= 0)
        group.bullet_impulses[static_cast<std::size_t>(rp.body_b)] +=
            pointWrench(-on_a, rp.lever_b);
      group.points.push_back(rp);
    }
  }
  return group;
}

void addRigidContactRows(NodeContactIsland& island, const RigidContactGroup& group,
                         const std::vector<int>& group_body, const RowDefaults& defaults,
                         double dt) {
  island.row_face.resize(island.rows.size(), -1);
  island.row_rigid.resize(island.rows.size(), -1);
  for (std::size_t i = 0; i < group.points.size(); ++i) {
    const RigidContactPoint& p = group.points[i];
    ContactRow row;
    row.frame = contactFrame(toEigen(p.point->m_normalWorldOnB));
    if (p.body_a >= 0) {
      row.terms.push_back(rigidPointTerm(group_body[static_cast<std::size_t>(p.body_a)], p.lever_a,
                                         +1.0, row.frame));
    } else {
      row.velocity_offset += row.frame * p.velocity_a;
    }
    if (p.body_b >= 0) {
      row.terms.push_back(rigidPointTerm(group_body[static_cast<std::size_t>(p.body_b)], p.lever_b,
                                         -1.0, row.frame));
    } else {
      row.velocity_offset -= row.frame * p.velocity_b;
    }
    row.mu = std::max(0.0, toDouble(p.point->m_combinedFriction));
    row.stiffness = defaults.stiffness;
    row.dissipation_time = defaults.dissipation_steps * dt;
    row.gap = toDouble(p.point->getDistance());
    row.lagged_normal_impulse = std::max(0.0, toDouble(p.point->m_appliedImpulse));
    island.rows.push_back(std::move(row));
    island.row_contact.push_back(-1);
    island.row_face.push_back(-1);
    island.row_rigid.push_back(static_cast<int>(i));
  }
}

std::vector<Eigen::Vector3d> rigidPointImpulses(const NodeContactIsland& island,
                                                const RigidContactGroup& group,
                                                const SapReport& report) {
  std::vector<Eigen::Vector3d> impulses(group.points.size(), Eigen::Vector3d::Zero());
  for (std::size_t r = 0; r < island.row_rigid.size(); ++r) {
    if (island.row_rigid[r] < 0) continue;
    impulses[static_cast<std::size_t>(island.row_rigid[r])] =
        island.rows[r].frame.transpose() * report.impulses[r];
  }
  return impulses;
}

void writeBackRigidImpulses(const RigidContactGroup& group,
                            const std::vector<Eigen::Vector3d>& impulses) {
  for (std::size_t i = 0; i < group.points.size() && i < impulses.size(); ++i) {
    btManifoldPoint& point = *group.points[i].point;
    const Eigen::Vector3d n = toEigen(point.m_normalWorldOnB);
    const double normal = n.dot(impulses[i]);
    const Eigen::Vector3d friction = impulses[i] - normal * n;
    const double slip = friction.norm();
    const Eigen::Vector3d dir1 = slip > 0 ? Eigen::Vector3d(friction / slip)
                                          : Eigen::Vector3d(contactFrame(n).row(0).transpose());
    point.m_appliedImpulse = toBtScalar(normal);
    point.m_lateralFrictionDir1 = toBt(dir1);
    point.m_appliedImpulseLateral1 = toBtScalar(slip);
    point.m_lateralFrictionDir2 = toBt(Eigen::Vector3d(n.cross(dir1)));
    point.m_appliedImpulseLateral2 = 0;
  }
}

}  // namespace torsion::sap
