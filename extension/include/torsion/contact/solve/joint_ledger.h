#pragma once
// What the world's joints (btTypedConstraint) did to their rigid bodies in one substep: what an
// island needs to take a jointed body from Bullet's rigid solver and solve it again with its
// joints as rows (rigid_joint_rows.h).
//
// Bullet records no joint impulse per body (a joint keeps one number, its last row's). So the
// ledger takes each jointed dynamic body's twist just before Bullet's solve
// (FemSoftBodySolver::predictMotion, after Bullet's damping), with the gyroscopic change Bullet's
// solver adds: the twist the body starts the step with, before forces and constraints. Bullet's
// joint impulse on the body is then what its velocity carries beyond that, its forces and its
// contact impulses,
//
//     w_joint = M (v_now - v_start) - dt (f, tau) - w_contact,
//
// until an island solves the body's joints: from then on the ledger holds the island's joint
// impulse (a second FEM body reaching the same body in the same substep undoes exactly that).
// Owned by FemSoftBodySolver, begun at each substep's predictMotion; read and written on the
// simulation thread only.

#include <BulletDynamics/ConstraintSolver/btTypedConstraint.h>
#include <BulletDynamics/Dynamics/btDynamicsWorld.h>

#include <map>
#include <optional>
#include <vector>

#include "torsion/contact/rigid_partner.h"

namespace torsion::sap {

class JointLedger {
 public:
  /// The substep begins (before Bullet's solve): records the world's enabled joints, Bullet's
  /// joint parameters (erp, cfm, damping) and each dynamic jointed body's starting twist.
  void begin(btDynamicsWorld& world, double dt);
  /// The joints to take into islands: those enabled in `world` now (a tick callback may have
  /// removed some since begin()). Call before the FEM step.
  void refresh(btDynamicsWorld& world);

  const std::vector<btTypedConstraint*>& joints() const { return joints_; }
  double erp() const { return erp_; }
  double globalCfm() const { return global_cfm_; }
  double damping() const { return damping_; }

  /// The twist (v, omega) `body` started the substep with (before forces and constraints), or
  /// nothing when it had no joint then.
  std::optional<Vector6d> startTwist(const btRigidBody& body) const;
  /// The joint impulse (N s; force, torque about the centre of mass) on `body` this substep:
  /// an island's once one solved it, else Bullet's from the body's velocity now, `contact_impulse`
  /// (Bullet's contact impulses on it) and `mass_matrix` (diag(m I, I_world)). Zero for a body
  /// without a joint at begin().
  Vector6d jointImpulse(const btRigidBody& body, const Vector6d& contact_impulse,
                        const Matrix6d& mass_matrix, double dt) const;
  /// An island solved `body`'s joints: their impulse on it this substep.
  void setIslandImpulse(const btRigidBody& body, const Vector6d& impulse);

 private:
  struct Entry {
    std::optional<Vector6d> start_twist;
    std::optional<Vector6d> island_impulse;
  };
  std::vector<btTypedConstraint*> joints_;
  std::map<const btRigidBody*, Entry> bodies_;  // looked up only, never iterated
  double erp_ = 0.2;
  double global_cfm_ = 0;
  double damping_ = 1;
};

}  // namespace torsion::sap
