#pragma once
// Multibody links as contact partners (docs/contact.md, "Multibody links"). A link collider of a
// Featherstone btMultiBody is not a btRigidBody: its motion is the multibody's generalised
// velocities qdot seen through the link's Jacobian J (6 x (6 + dofs), rows (v, omega) at the
// link's reference point). For the contact solve the link is a rigid partner whose 6 velocities
// V = J qdot are CG unknowns with the effective mass Lambda = (J M^-1 J^T)^-1: eliminating qdot
// under V = J qdot from 1/2 (qdot - qdot0)^T M (qdot - qdot0) leaves 1/2 (V - V0)^T Lambda
// (V - V0), so one link's exchange of momentum is as implicit and exact as a rigid body's. After
// the solve the impulse on the link goes to the multibody as dqdot = M^-1 J^T F (what Bullet's
// own multibody contacts use), with the pose corrected by dt dqdot.
//
// Approximations: J M^-1 J^T is singular in the directions a link cannot move (a fixed base, a
// joint's locked axes); there the link yields within the solve as a body 1e6 times its own mass
// and inertia would (the impulse the multibody then receives moves it only where it can move);
// J and M^-1 are taken at Bullet's configuration of the step (J after its integration, M^-1 as
// cached by its forward dynamics); two links of one multibody touched in the same step are
// separate partners within the solve: each sees the multibody's inertia behind it, and the others'
// impulses enter its entry velocity lagged by one step (J_a M^-1 sum_b J_b^T F_b of the last
// step), exact when the impulses are steady (a held object); the multibody then receives every
// impulse exactly. Joint motors and limits are Bullet's constraints, solved before the FEM step:
// they answer the contact impulse one step later.
// Touched only by the simulation thread.

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>
#include <BulletDynamics/Featherstone/btMultiBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include <Eigen/Core>
#include <map>
#include <optional>
#include <vector>

#include "torsion/contact/rigid_partner.h"

namespace torsion {

/// `object` as a multibody link collider, or null.
btMultiBodyLinkCollider* asMultibodyLink(const btCollisionObject* object);

/// The Jacobian of a link's motion (v, omega) at world point `point`: V = J qdot, qdot Bullet's
/// velocity vector (base omega, base v, joint velocities), 6 x (6 + dofs).
Eigen::MatrixXd linkJacobian(const btMultiBodyLinkCollider& link, const Eigen::Vector3d& point);

/// The multibody's velocity change for a generalised impulse `impulse` (6 + dofs): M^-1 impulse,
/// with the articulated inertia Bullet cached at its last forward-dynamics pass.
Eigen::VectorXd multibodyResponse(const btMultiBody& body, const Eigen::VectorXd& impulse);

/// The link colliders a body touches in a step: their start-of-step poses and, as partners, their
/// velocities, effective masses and the write-back of the contact impulse.
class MultibodyLinks {
 public:
  /// Stage 1: forgets last step's poses.
  void beginStep() { start_poses_.clear(); }
  /// Stage 2 (a broadphase pair): records a link's pose, which is still the start-of-step pose
  /// (Bullet moves links only in stage 3). Ignores any other object.
  void recordStartPose(const btCollisionObject* object);
  /// The recorded start pose of `object`, if it is a link seen in stage 2.
  std::optional<btTransform> startPose(const btCollisionObject& object) const;
  /// Bound on the speed of any point of the link's shape (`radius` about its reference point).
  static double speedBound(const btCollisionObject& object, double radius);

  /// Fills a partner for a link collider (its `com` set to the reference point): entry velocity
  /// J qdot plus the lagged response to last step's impulses on the multibody's other links,
  /// dynamic unless the link and its ancestors are static or kinematic, effective mass.
  /// Returns false (partner untouched) when `object` is not a link.
  bool describe(const btCollisionObject* object, RigidPartner& partner) const;
  /// After the step: each link partner's impulse onto its multibody (velocities and joint
  /// positions), remembered for the next step's lagged coupling.
  void applyImpulses(const std::vector<RigidPartner>& partners, double dt);

 private:
  struct LinkImpulse {
    const btMultiBodyLinkCollider* link;
    Eigen::Vector3d point;  // m, where the wrench acts
    Vector6d impulse;       // (force, torque about point) x dt
  };
  std::map<const btCollisionObject*, btTransform> start_poses_;
  static void applyImpulse(const LinkImpulse& l, double dt);
  std::vector<LinkImpulse> last_impulses_;
};

}  // namespace torsion
