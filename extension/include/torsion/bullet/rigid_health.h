#pragma once
// Is every rigid body still a number? Bullet integrates a body whose shape or state overflowed
// (a hull margin or a sphere radius of 1e300, an enormous impulse) into NaN without complaint;
// the FEM side has its own health check (StepReport), this is the rigid side's. Call it after
// each step and treat a fault as the simulation going unstable.
//
//   std::vector<NamedRigidBody> bodies = {{"lid", lid}, {"ball", ball}};
//   if (auto fault = findUnhealthyRigidBody(bodies)) fail(fault->message);

#include <optional>
#include <string>
#include <vector>

class btDynamicsWorld;
class btRigidBody;

namespace torsion {

/// Beyond this magnitude (m, m/s, rad/s) a coordinate is taken as overflowing: its square, which
/// Bullet forms in every dot product and inertia, would leave the double range.
inline constexpr double kRigidMagnitudeLimit = 1e150;

struct NamedRigidBody {
  std::string name;
  const btRigidBody* body = nullptr;
};

struct RigidBodyFault {
  const btRigidBody* body = nullptr;
  std::string name;
  /// "rigid body 'ball': position is not finite (nan, nan, nan)"
  std::string message;
};

/// The first body (in list order) whose position, orientation, linear or angular velocity is not
/// finite or beyond kRigidMagnitudeLimit; nothing when all are healthy.
std::optional<RigidBodyFault> findUnhealthyRigidBody(const std::vector<NamedRigidBody>& bodies);

/// The same over every rigid body of a world, in the world's order, named "#<index>" (the index
/// among its collision objects) as the world keeps no names.
std::optional<RigidBodyFault> findUnhealthyRigidBody(const btDynamicsWorld& world);

}  // namespace torsion
