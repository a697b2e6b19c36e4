#pragma once
// The dynamic rigid bodies a convex island takes from Bullet's rigid solver in one step, their
// contact points and their joints' rows: plain data, what RigidContactSolver keeps from detection
// to the step's end (gathered and turned into rows by rigid_contact_rows.h, which explains the
// model).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "torsion/contact/rigid_partner.h"

class btManifoldPoint;
class btRigidBody;
class btTypedConstraint;

namespace torsion::sap {

/// One contact point Bullet found for a body of the group.
struct RigidContactPoint {
  btManifoldPoint* point = nullptr;
  /// The group's index of Bullet's body A and body B, or -1 for a static or kinematic object.
  int body_a = -1;
  int body_b = -1;
  /// The point on each body less that body's centre of mass at the step's start (m, world).
  Eigen::Vector3d lever_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d lever_b = Eigen::Vector3d::Zero();
  /// A prescribed side's point velocity (m/s, world); zero for a dynamic side.
  Eigen::Vector3d velocity_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_b = Eigen::Vector3d::Zero();
};

/// One row of a joint between bodies of the group (btTypedConstraint::getInfo2 at the step's
/// start: rigid_joint_rows.h). Bullet's convention: the row's velocity is
/// jacobian_a . twist_a + jacobian_b . twist_b (J2's sign included), and its impulse lambda acts
/// on A as lambda jacobian_a, on B as lambda jacobian_b.
struct RigidJointRow {
  btTypedConstraint* joint = nullptr;
  /// The group's index of the joint's body A and body B, or -1 for a static or kinematic body.
  int body_a = -1;
  int body_b = -1;
  Vector6d jacobian_a = Vector6d::Zero();  ///< (linear; angular), twists about the centres of mass
  Vector6d jacobian_b = Vector6d::Zero();
  /// The row's velocity from its static or kinematic sides (m/s or rad/s).
  double prescribed_velocity = 0;
  double target_velocity = 0;  ///< Bullet's right-hand side: erp / dt times the error, or a motor's
  double lower = 0;            ///< impulse bounds (N s), the breaking threshold included
  double upper = 0;
  double cfm = 0;  ///< Bullet's constraint force mixing (relative to the row's Delassus entry)
};

/// The dynamic rigid bodies an island takes from Bullet's rigid solver this step.
struct RigidContactGroup {
  std::vector<btRigidBody*> bodies;
  /// Per body: w_bullet, Bullet's contact impulses on it (N s; force, torque about the centre of
  /// mass at the step's start). Its joint impulses: JointLedger.
  std::vector<Vector6d> bullet_impulses;
  std::vector<RigidContactPoint> points;
  /// The joints with a body in the group (each once) and their rows, joint by joint.
  std::vector<btTypedConstraint*> joints;
  std::vector<RigidJointRow> joint_rows;
  /// Why bodies reached from the seeds stay with Bullet (one line each); empty when all were
  /// taken.
  std::vector<std::string> kept_by_bullet;

  bool contains(const btRigidBody* body) const;
};

}  // namespace torsion::sap
