#include "py_contacts.h"

#include <BulletCollision/CollisionShapes/btStaticPlaneShape.h>
#include <BulletSoftBody/btSoftBody.h>

#include "torsion/bt_conversions.h"

namespace torsion::python {

namespace {

// A rigid object's name as Python knows it: a scene or added rigid body's, "ground" for the
// ground plane (the one static plane the world has), "" for anything else.
std::string partnerName(PyWorld& world, const btCollisionObject* object) {
  if (const btRigidBody* body = btRigidBody::upcast(object)) {
    if (const scene::SceneRigidBody* named = world.sceneRigidBody(*body)) return named->name;
  }
  if (object != nullptr && object->getCollisionShape() != nullptr &&
      object->getCollisionShape()->getShapeType() == STATIC_PLANE_PROXYTYPE) {
    return "ground";
  }
  return "";
}

void add(ContactList& list, const std::string& a, const std::string& b,
         const Eigen::Vector3d& point, const Eigen::Vector3d& normal,
         const Eigen::Vector3d& impulse) {
  list.body_a.push_back(a);
  list.body_b.push_back(b);
  list.points.insert(list.points.end(), point.data(), point.data() + 3);
  list.normals.insert(list.normals.end(), normal.data(), normal.data() + 3);
  list.impulses.insert(list.impulses.end(), impulse.data(), impulse.data() + 3);
}

void addFemRigidContacts(PyWorld& world, const FemBody& body, ContactList& list) {
  const RigidContactSolver& solver = body.contacts();
  const std::vector<RigidPartner>& partners = solver.partners();
  auto partner = [&](int index) {
    return index >= 0 && static_cast<size_t>(index) < partners.size()
               ? partnerName(world, partners[static_cast<size_t>(index)].object)
               : std::string();
  };
  // Every contact that gave an impulse: one that let go this step may still carry friction (its
  // bound lags by a step, docs/contact-sap.md, "Limits").
  for (const NodeContact& c : solver.contacts()) {
    if (c.anchored || c.impulse.isZero(0)) continue;
    add(list, body.name(), partner(c.partner), body.state().position(c.node), c.normal, c.impulse);
  }
  for (const FaceContact& f : solver.solvedFaceContacts()) {
    if (f.impulse.isZero(0)) continue;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < 3; ++k)
      point += f.weights[static_cast<Eigen::Index>(k)] * body.state().position(f.nodes[k]);
    add(list, body.name(), partner(f.partner), point, f.normal, f.impulse);
  }
}

void addRigidRigidContacts(PyWorld& world, ContactList& list) {
  btDispatcher* dispatcher = world.world().bulletWorld().getDispatcher();
  for (int m = 0; m < dispatcher->getNumManifolds(); ++m) {
    const btPersistentManifold* manifold = dispatcher->getManifoldByIndexInternal(m);
    const btCollisionObject* a = manifold->getBody0();
    const btCollisionObject* b = manifold->getBody1();
    if (btRigidBody::upcast(a) == nullptr || btRigidBody::upcast(b) == nullptr) continue;
    for (int k = 0; k < manifold->getNumContacts(); ++k) {
      const btManifoldPoint& p = manifold->getContactPoint(k);
      if (!(p.getDistance() <= 0 || p.getAppliedImpulse() > 0)) continue;
      // Bullet's impulses on A: along the normal (B to A) and its friction directions (set only
      // where a friction impulse was solved).
      btVector3 impulse = p.m_normalWorldOnB * p.getAppliedImpulse();
      if (p.m_appliedImpulseLateral1 != 0)
        impulse += p.m_lateralFrictionDir1 * p.m_appliedImpulseLateral1;
      if (p.m_appliedImpulseLateral2 != 0)
        impulse += p.m_lateralFrictionDir2 * p.m_appliedImpulseLateral2;
      add(list, partnerName(world, a), partnerName(world, b), toEigen(p.getPositionWorldOnA()),
          toEigen(p.m_normalWorldOnB), toEigen(impulse));
    }
  }
}

}  // namespace

ContactList lastStepContacts(PyWorld& world) {
  ContactList list;
  if (!world.stepped()) return list;
  for (const auto& body : world.world().bodies())
    addFemRigidContacts(world, *body, list);
  addRigidRigidContacts(world, list);
  return list;
}

}  // namespace torsion::python
