// FEM-rigid node contacts inside an island's joint solve (docs/contact.md, "Contact between FEM
// bodies", "Islands on rigid ground"): with every partner prescribed, a sticking contact fixes the
// node's velocity and a sliding one its normal component, exactly as the reduced system of
// rigid_contact_reduced_system.cpp does with no rigid unknowns; so the island's projected CG can
// filter them with the body's own constraints, and the active set (rigid_contact_active_set.cpp)
// runs between the island's solves on the impulses the joint system leaves on them.

#include <algorithm>

#include "torsion/contact/rigid_contact.h"

namespace torsion {

bool RigidContactSolver::joinsIsland() const {
  if (!faces_.empty()) return false;
  return std::none_of(partners_.begin(), partners_.end(),
                      [](const RigidPartner& k) { return k.dynamic || k.link != nullptr; });
}

void RigidContactSolver::beginIslandSolve(const NodeConstraints& base) {
  base_ = &base;
  numberRigidUnknowns();  // none: every partner is prescribed (joinsIsland)
}

void RigidContactSolver::islandConstraints(const Eigen::VectorXd& b, NodeConstraints& out,
                                           Eigen::VectorXd& b_friction) const {
  out = *base_;
  b_friction = b;
  for (const NodeContact& c : contacts_) {
    // A node the body's own constraints prescribe (a hand, a node group) ignores the contact,
    // as in the reduced system (expand()).
    if (c.held || c.state == NodeContact::State::kInactive || base_->isConstrained(c.node))
      continue;
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d rigid = pointVelocity(k.entry_velocity, c.lever);
    // End gap gap + dt n.(v_i - J_i V) = 0 along the normal.
    const double normal_speed = c.normal.dot(rigid) - c.gap / dt_;
    if (c.state == NodeContact::State::kStick) {
      out.prescribeVelocity(c.node,
                            rigid - c.normal * c.normal.dot(rigid) + c.normal * normal_speed);
    } else {
      out.prescribeDirection(c.node, c.normal, normal_speed);
      b_friction.segment<3>(3 * c.node) += c.friction_impulse;
    }
  }
}

bool RigidContactSolver::updateIslandActiveSet(const Eigen::VectorXd& v,
                                               const Eigen::VectorXd& impulses) {
  product_ = impulses;
  ++stats_.active_set_iterations;
  measureFrictionShares();
  return updateActiveSet(v, product_, dt_);
}

void RigidContactSolver::endIslandSolve(const Eigen::VectorXd& v, bool active_set_converged) {
  stats_.active_set_converged = active_set_converged;
  collectImpulses();
  solveHeld(v, dt_);
  measureEndGaps(v);
}

}  // namespace torsion
