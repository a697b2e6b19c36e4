#pragma once
// The dynamic rigid bodies a convex island takes from Bullet's rigid solver in one step, and their
// contact points: plain data, what RigidContactSolver keeps from detection to the step's end
// (gathered and turned into rows by rigid_contact_rows.h, which explains the model).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "torsion/contact/rigid_partner.h"

class btManifoldPoint;
class btRigidBody;

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

/// The dynamic rigid bodies an island takes from Bullet's rigid solver this step.
struct RigidContactGroup {
  std::vector<btRigidBody*> bodies;
  /// Per body: w_bullet (N s; force, torque about the centre of mass at the step's start).
  std::vector<Vector6d> bullet_impulses;
  std::vector<RigidContactPoint> points;
  /// Why bodies reached from the seeds stay with Bullet (one line each); empty when all were
  /// taken.
  std::vector<std::string> kept_by_bullet;

  bool contains(const btRigidBody* body) const;
};

}  // namespace torsion::sap
