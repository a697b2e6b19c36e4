// The reduced system of the FEM-rigid contact solve (docs/contact.md, "Resolution"): node
// velocities expressed through the active contacts and the dynamic rigid velocities, its
// operator, right-hand side and block-Jacobi preconditioner, and the CG that solves it.

#include <Eigen/Dense>

#include "torsion/contact/rigid_contact.h"
#include "torsion/solve/pcg_iterations.h"

namespace torsion {

// Unknowns q = (u, V): u (3n) the free node velocity components, V (6 per dynamic partner) the
// rigid velocities. Node velocities are v = T q + v_c:
//   free node              v_i = u_i
//   held node              v_i = S_i u_i (= 0 for a fully prescribed node)      + prescribed
//   sliding on partner k   v_i = P_n u_i + n n.(J_i V_k)  (the second term if k is dynamic)
//   sticking on partner k  v_i = J_i V_k                   (if k is dynamic)
// with v_c holding the prescribed parts (node groups, the gap closure -gap/dt along n, a static
// or kinematic partner's surface velocity). The reduced operator is T^T A T + diag(M_k), the
// reduced right-hand side T^T (b - A v_c) + M_k V_k(Bullet) - sum J^T f (sliding friction).

void RigidContactSolver::expand(const Eigen::VectorXd& q, Eigen::VectorXd& v) const {
  const int n = model_->nodeCount();
  v.resize(3 * n);
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    Eigen::Vector3d u = q.segment<3>(3 * i);
    if (base_->isConstrained(i)) {
      v.segment<3>(3 * i) = base_->filterNode(i, u);
      continue;
    }
    if (ci < 0 || contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kInactive) {
      v.segment<3>(3 * i) = u;
      continue;
    }
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d& nrm = c.normal;
    Eigen::Vector3d vi = Eigen::Vector3d::Zero();
    Eigen::Vector3d rigid = Eigen::Vector3d::Zero();
    if (k.dynamic) rigid = pointVelocity(q.segment<6>(k.unknown), c.lever);
    if (c.state == NodeContact::State::kSlide) {
      vi = u - nrm * nrm.dot(u) + nrm * nrm.dot(rigid);
    } else {
      vi = rigid;
    }
    v.segment<3>(3 * i) = vi;
  }
}

void RigidContactSolver::contract(const Eigen::VectorXd& y, const Eigen::VectorXd& rigid_part,
                                  Eigen::VectorXd& q) const {
  const int n = model_->nodeCount();
  q.resize(3 * n + 6 * dynamic_count_);
  q.tail(6 * dynamic_count_) = rigid_part;
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    const Eigen::Vector3d yi = y.segment<3>(3 * i);
    if (base_->isConstrained(i)) {
      q.segment<3>(3 * i) = base_->filterNode(i, yi);
      continue;
    }
    if (ci < 0 || contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kInactive) {
      q.segment<3>(3 * i) = yi;
      continue;
    }
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    const Eigen::Vector3d& nrm = c.normal;
    if (c.state == NodeContact::State::kSlide) {
      q.segment<3>(3 * i) = yi - nrm * nrm.dot(yi);
      if (k.dynamic) q.segment<6>(k.unknown) += pointWrench(nrm * nrm.dot(yi), c.lever);
    } else {
      q.segment<3>(3 * i).setZero();
      if (k.dynamic) q.segment<6>(k.unknown) += pointWrench(yi, c.lever);
    }
  }
}

void RigidContactSolver::applyOperator(const SystemOperator& op, const Eigen::VectorXd& q,
                                       Eigen::VectorXd& out) {
  expand(q, scratch_);
  op.multiply(scratch_, product_);
  rigid_scratch_.resize(6 * dynamic_count_);
  for (const RigidPartner& k : partners_) {
    if (!k.dynamic) continue;
    const int o = k.unknown - 3 * model_->nodeCount();
    rigid_scratch_.segment<6>(o) = partnerMomentum(k, q.segment<6>(k.unknown));
  }
  faces_.addProduct(scratch_, q, partners_, 3 * model_->nodeCount(), product_, rigid_scratch_);
  addSlipResistance(q, scratch_, product_, rigid_scratch_);
  contract(product_, rigid_scratch_, out);
}

void RigidContactSolver::addSlipResistance(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                                           Eigen::VectorXd& node_out,
                                           Eigen::VectorXd& rigid_out) const {
  // R (v_i - J_i V) on a sliding node (its friction's resistance to a slip across it), and the
  // opposite wrench on a dynamic partner. A static or kinematic partner's given velocity is on the
  // right-hand side (assembleRightHandSide).
  const int n = model_->nodeCount();
  for (const NodeContact& c : contacts_) {
    if (c.held || c.state != NodeContact::State::kSlide || c.slip_resistance.isZero(0)) continue;
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    Eigen::Vector3d slip = v.segment<3>(3 * c.node);
    if (k.dynamic) slip -= pointVelocity(q.segment<6>(k.unknown), c.lever);
    const Eigen::Vector3d y = c.slip_resistance * slip;
    node_out.segment<3>(3 * c.node) += y;
    if (k.dynamic) rigid_out.segment<6>(k.unknown - 3 * n) -= pointWrench(y, c.lever);
  }
}

void RigidContactSolver::buildPreconditioner(const SystemOperator& op) {
  const int n = model_->nodeCount();
  op.diagonalBlocks(block_inverse_);
  rigid_inverse_.assign(partners_.size(), Eigen::Matrix<double, 6, 6>::Zero());
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (!partners_[k].dynamic) continue;
    rigid_inverse_[k] = partners_[k].mass_matrix;
  }
  faces_.addPreconditioner(block_inverse_, rigid_inverse_, partners_);
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    if (ci < 0 || base_->isConstrained(i)) continue;
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    if (c.state == NodeContact::State::kInactive ||
        !partners_[static_cast<size_t>(c.partner)].dynamic)
      continue;
    // G_i^T D_i G_i with G_i = n n^T J_i (slide) or J_i (stick).
    Eigen::Matrix<double, 3, 6> J;
    J << Eigen::Matrix3d::Identity(), -(Eigen::Matrix3d() << 0, -c.lever.z(), c.lever.y(),
                                        c.lever.z(), 0, -c.lever.x(), -c.lever.y(), c.lever.x(), 0)
                                           .finished();
    Eigen::Matrix<double, 3, 6> G = J;
    if (c.state == NodeContact::State::kSlide) G = c.normal * (c.normal.transpose() * J);
    rigid_inverse_[static_cast<size_t>(c.partner)] +=
        G.transpose() * block_inverse_[static_cast<size_t>(i)] * G;
    if (c.state == NodeContact::State::kSlide)
      rigid_inverse_[static_cast<size_t>(c.partner)] += J.transpose() * c.slip_resistance * J;
  }
  for (const NodeContact& c : contacts_) {
    if (!c.held && c.state == NodeContact::State::kSlide && !base_->isConstrained(c.node))
      block_inverse_[static_cast<size_t>(c.node)] += c.slip_resistance;
  }
  for (auto& block : block_inverse_)
    block = block.inverse().eval();
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (partners_[k].dynamic) rigid_inverse_[k] = rigid_inverse_[k].inverse().eval();
  }
}

void RigidContactSolver::precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  const int n = model_->nodeCount();
  z.resize(r.size());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d zi = block_inverse_[static_cast<size_t>(i)] * r.segment<3>(3 * i);
    const int ci = node_contact_[static_cast<size_t>(i)];
    if (base_->isConstrained(i)) {
      z.segment<3>(3 * i) = base_->filterNode(i, zi);
    } else if (ci < 0 ||
               contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kInactive) {
      z.segment<3>(3 * i) = zi;
    } else if (contacts_[static_cast<size_t>(ci)].state == NodeContact::State::kSlide) {
      const Eigen::Vector3d& nrm = contacts_[static_cast<size_t>(ci)].normal;
      z.segment<3>(3 * i) = zi - nrm * nrm.dot(zi);
    } else {
      z.segment<3>(3 * i).setZero();
    }
  }
  for (size_t k = 0; k < partners_.size(); ++k) {
    if (!partners_[k].dynamic) continue;
    const int o = partners_[k].unknown;
    z.segment<6>(o) = rigid_inverse_[k] * r.segment<6>(o);
  }
}

LinearSolveReport RigidContactSolver::conjugateGradient(const SystemOperator& op,
                                                        const Eigen::VectorXd& reduced_rhs,
                                                        const SolverSettings& settings,
                                                        Eigen::VectorXd& q) {
  applyOperator(op, q, cg_.q);
  r_ = reduced_rhs - cg_.q;
  return pcgIterations(
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) { applyOperator(op, in, out); },
      [&](const Eigen::VectorXd& in, Eigen::VectorXd& out) { precondition(in, out); },
      reduced_rhs.norm(), settings, q, r_, cg_);
}

void RigidContactSolver::numberRigidUnknowns() {
  const int n = model_->nodeCount();
  dynamic_count_ = 0;
  for (RigidPartner& k : partners_) {
    if (!k.dynamic) continue;
    k.unknown = 3 * n + 6 * dynamic_count_++;
  }
  for (RigidPartner& k : partners_)
    k.velocity = k.entry_velocity;
}

void RigidContactSolver::warmStart(const Eigen::VectorXd& v) {
  // The given node velocities, Bullet's rigid velocities.
  const int n = model_->nodeCount();
  q_.resize(3 * n + 6 * dynamic_count_);
  q_.head(3 * n) = v;
  for (const RigidPartner& k : partners_) {
    if (k.dynamic) q_.segment<6>(k.unknown) = k.entry_velocity;
  }
}

void RigidContactSolver::assembleRightHandSide(const SystemOperator& op, const Eigen::VectorXd& b) {
  const int n = model_->nodeCount();
  const double dt = dt_;
  // Prescribed parts v_c and the friction impulses.
  v_c_.setZero(3 * n);
  base_->impose(v_c_);
  b_friction_ = b;
  rigid_rhs_.resize(6 * dynamic_count_);
  for (const RigidPartner& k : partners_) {
    if (!k.dynamic) continue;
    const int o = k.unknown - 3 * n;
    rigid_rhs_.segment<6>(o) = partnerMomentum(k, k.entry_velocity);
  }
  for (const NodeContact& c : contacts_) {
    if (c.held || c.state == NodeContact::State::kInactive) continue;
    const RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    // End gap gap + dt n.(v_i - J_i V) = 0: the node closes the gap relative to the rigid
    // surface, whose velocity is an unknown (dynamic) or given (static, kinematic).
    Eigen::Vector3d vc = c.normal * (-c.gap / dt);
    if (!k.dynamic) {
      const Eigen::Vector3d rigid = pointVelocity(k.entry_velocity, c.lever);
      vc += c.state == NodeContact::State::kStick ? rigid
                                                  : Eigen::Vector3d(c.normal * c.normal.dot(rigid));
    }
    v_c_.segment<3>(3 * c.node) = vc;
    if (c.state == NodeContact::State::kSlide) {
      b_friction_.segment<3>(3 * c.node) += c.friction_impulse;
      if (!k.dynamic)
        b_friction_.segment<3>(3 * c.node) +=
            c.slip_resistance * pointVelocity(k.entry_velocity, c.lever);
      if (k.dynamic)
        rigid_rhs_.segment<6>(k.unknown - 3 * n) -= pointWrench(c.friction_impulse, c.lever);
    }
  }
  b_solve_ = b_friction_;
  faces_.addRightHandSide(v_c_, partners_, dt, 3 * n, b_solve_, rigid_rhs_);
  op.multiply(v_c_, product_);
  contract(b_solve_ - product_, rigid_rhs_, reduced_rhs_);
}

void RigidContactSolver::projectWarmStart() {
  // Keep the warm start inside the reduced space (the rigid part is kept as is).
  const int n = model_->nodeCount();
  Eigen::VectorXd u = q_.head(3 * n);
  for (int i = 0; i < n; ++i) {
    const int ci = node_contact_[static_cast<size_t>(i)];
    Eigen::Vector3d ui = u.segment<3>(3 * i);
    if (base_->isConstrained(i)) {
      ui = base_->filterNode(i, ui);
    } else if (ci >= 0) {
      const NodeContact& c = contacts_[static_cast<size_t>(ci)];
      if (c.state == NodeContact::State::kSlide) ui -= c.normal * c.normal.dot(ui);
      if (c.state == NodeContact::State::kStick) ui.setZero();
    }
    q_.segment<3>(3 * i) = ui;
  }
}

void RigidContactSolver::recoverSolution(const SystemOperator& op, Eigen::VectorXd& v) {
  expand(q_, v);
  v += v_c_;
  for (RigidPartner& k : partners_) {
    if (k.dynamic) k.velocity = q_.segment<6>(k.unknown);
  }
  // Constraint impulses on the nodes: A v - b less the friction and the face contacts'
  // impulses (neither is a node's constraint impulse).
  op.multiply(v, product_);
  product_ -= b_friction_;
  faces_.takeImpulses(v, partners_, dt_, product_);
}

}  // namespace torsion
