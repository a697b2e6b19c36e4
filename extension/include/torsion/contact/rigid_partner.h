#pragma once
// A rigid object that FEM nodes or faces touch during one step (docs/contact.md), and the
// kinematics of a point on it. Touched only by the simulation thread.

#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletDynamics/Featherstone/btMultiBodyLinkCollider.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace torsion {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// A rigid object touched this step.
struct RigidPartner {
  const btCollisionObject* object = nullptr;
  btRigidBody* body = nullptr;  ///< null for a plain collision object or a multibody link
  /// A link (or base) of a Featherstone multibody: its velocities and response come from the
  /// multibody (contact/multibody_partner.h); null otherwise.
  btMultiBodyLinkCollider* link = nullptr;
  bool dynamic = false;  ///< velocities solved with the body's; else prescribed
  /// A dynamic body touching a static or kinematic one in Bullet (a box on the ground): solved
  /// as prescribed here, its contact impulse goes to Bullet's rigid solver (one step later), which
  /// alone knows its other contacts. Never in the convex solve when its island can take those
  /// contacts as rows (contact/solve/rigid_contact_rows.h).
  bool supported = false;
  double mass = 0;
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();          ///< world, kg m^2 (dynamic)
  Eigen::Matrix3d inverse_inertia = Eigen::Matrix3d::Zero();  ///< world (dynamic)
  /// Effective mass of the body's motion (v, omega) at `com`, world (dynamic): diag(m, I) for a
  /// rigid body, (J M^-1 J^T)^-1 for a multibody link (regularised in its locked directions).
  Matrix6d mass_matrix = Matrix6d::Zero();
  Matrix6d inverse_mass_matrix = Matrix6d::Zero();  ///< its inverse (velocity per impulse)
  Eigen::Vector3d com = Eigen::Vector3d::Zero();
  Vector6d entry_velocity = Vector6d::Zero();  ///< (v, omega) Bullet integrated with
  Vector6d velocity = Vector6d::Zero();        ///< (v, omega) current estimate / result
  Vector6d impulse = Vector6d::Zero();         ///< (force, torque about com) x dt from this body
  /// The impulse (force, torque about com) of Bullet's contacts with other rigid objects this
  /// step, which the convex island solves afresh as rows (contact/solve/rigid_contact_rows.h):
  /// the body's momentum before contact is M entry_velocity less it. Zero otherwise.
  Vector6d bullet_contact_impulse = Vector6d::Zero();
  /// A dynamic body that another FEM body of the same convex island also touches, and whose
  /// solved velocity that body applies (contact/solve/convex_rows.h): finish() leaves it alone.
  bool applied_by_another_body = false;
};

/// M V: the partner's momentum (linear, angular about com) at velocity V (dynamic partners). A
/// rigid body's from m and I directly (the same arithmetic as before multibody partners, so rigid
/// scenes are unchanged to the bit); a link's from its 6x6 effective mass.
inline Vector6d partnerMomentum(const RigidPartner& k, const Vector6d& V) {
  if (k.link != nullptr) return k.mass_matrix * V;
  Vector6d p;
  p << k.mass * V.head<3>(), k.inertia * V.tail<3>();
  return p;
}

/// M^-1 w: the partner's velocity change for an impulse wrench w (dynamic or supported partners).
inline Vector6d partnerResponse(const RigidPartner& k, const Vector6d& w) {
  if (k.link != nullptr) return k.inverse_mass_matrix * w;
  Vector6d dv;
  dv << w.head<3>() / k.mass, k.inverse_inertia * w.tail<3>();
  return dv;
}

/// Velocity of the rigid point at lever r (from the centre of mass): J V = v + omega x r.
inline Eigen::Vector3d pointVelocity(const Vector6d& V, const Eigen::Vector3d& r) {
  return V.head<3>() + V.tail<3>().cross(r);
}

/// J, the 3x6 map from a partner's (v, omega) to the velocity of its point at lever r:
/// J V = v + omega x r = v - [r]x omega.
inline Eigen::Matrix<double, 3, 6> pointJacobian(const Eigen::Vector3d& r) {
  Eigen::Matrix<double, 3, 6> J;
  J << Eigen::Matrix3d::Identity(),
      (Eigen::Matrix3d() << 0, r.z(), -r.y(), -r.z(), 0, r.x(), r.y(), -r.x(), 0).finished();
  return J;
}

/// J^T y = (y, r x y): the wrench about the centre of mass of a point impulse y at lever r.
inline Vector6d pointWrench(const Eigen::Vector3d& y, const Eigen::Vector3d& r) {
  Vector6d w;
  w << y, r.cross(y);
  return w;
}

}  // namespace torsion
