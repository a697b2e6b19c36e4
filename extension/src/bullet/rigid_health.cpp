#include "torsion/bullet/rigid_health.h"

#include <btBulletDynamicsCommon.h>

#include <cmath>
#include <sstream>

namespace torsion {

namespace {

bool carried(btScalar v) {
  const double x = static_cast<double>(v);  // float Bullet: widened exactly
  return std::isfinite(x) && std::abs(x) <= kRigidMagnitudeLimit;
}

bool carried(const btVector3& v) {
  return carried(v.x()) && carried(v.y()) && carried(v.z());
}

std::string describe(const btVector3& v) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << static_cast<double>(v.x()) << ", " << static_cast<double>(v.y()) << ", "
    << static_cast<double>(v.z()) << ")";
  return s.str();
}

// The first unhealthy quantity of one body, or an empty string.
std::string faultOf(const btRigidBody& body) {
  const btTransform& t = body.getCenterOfMassTransform();
  const btQuaternion q = t.getRotation();
  const btVector3 orientation(q.x(), q.y(), q.z());
  const char* bound = " is not finite or beyond 1e150 ";
  if (!carried(t.getOrigin())) return "position" + (bound + describe(t.getOrigin()));
  if (!carried(orientation) || !carried(q.w())) return "orientation is not finite";
  if (!carried(body.getLinearVelocity()))
    return "linear velocity" + (bound + describe(body.getLinearVelocity()));
  if (!carried(body.getAngularVelocity()))
    return "angular velocity" + (bound + describe(body.getAngularVelocity()));
  return {};
}

}  // namespace

std::optional<RigidBodyFault> findUnhealthyRigidBody(const std::vector<NamedRigidBody>& bodies) {
  for (const NamedRigidBody& b : bodies) {
    if (b.body == nullptr) continue;
    if (std::string fault = faultOf(*b.body); !fault.empty())
      return RigidBodyFault{b.body, b.name, "rigid body '" + b.name + "': " + fault};
  }
  return std::nullopt;
}

std::optional<RigidBodyFault> findUnhealthyRigidBody(const btDynamicsWorld& world) {
  // The FEM solver calls this every substep: no list and no names unless a body is at fault.
  const btCollisionObjectArray& objects = world.getCollisionObjectArray();
  for (int i = 0; i < objects.size(); ++i) {
    const btRigidBody* body = btRigidBody::upcast(objects[i]);
    if (body == nullptr) continue;
    if (std::string fault = faultOf(*body); !fault.empty()) {
      return findUnhealthyRigidBody({{"#" + std::to_string(i), body}});
    }
  }
  return std::nullopt;
}

}  // namespace torsion
