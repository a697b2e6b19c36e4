#include "torsion/haptics/contact_stiffness.h"

#include <map>

#include "torsion/bullet/fem_body.h"

namespace torsion::haptics {

std::optional<ContactPatch> contactPatch(const FemBody& body, const btCollisionObject& tool) {
  const RigidContactSolver& contacts = body.contacts();
  const std::vector<RigidPartner>& partners = contacts.partners();
  auto touches = [&](int partner) {
    return partner >= 0 && static_cast<std::size_t>(partner) < partners.size() &&
           partners[static_cast<std::size_t>(partner)].object == &tool;
  };
  std::map<int, double> share;  // node -> N s of push (ordered: the same sums every run)
  Eigen::Vector3d push = Eigen::Vector3d::Zero();
  for (const NodeContact& c : contacts.contacts()) {
    if (!touches(c.partner) || c.state == NodeContact::State::kInactive || c.held) continue;
    share[c.node] += c.impulse.norm();
    push -= c.impulse;  // the rigid body gave the node `impulse`: the tool is pushed back
  }
  for (const FaceContact& f : contacts.solvedFaceContacts()) {
    if (!touches(f.partner) || f.state == FaceContact::State::kInactive) continue;
    for (int k = 0; k < 3; ++k) {
      if (f.weights[k] > 0)
        share[f.nodes[static_cast<std::size_t>(k)]] += f.weights[k] * f.impulse.norm();
    }
    push -= f.impulse;
  }
  double total = 0;
  for (const auto& [node, impulse] : share)
    total += impulse;
  if (!(total > 0) || push.norm() == 0) return std::nullopt;
  ContactPatch patch;
  patch.normal = -push.normalized();  // the tool pushes the body the other way
  patch.centre.setZero();
  for (const auto& [node, impulse] : share) {
    patch.load.emplace_back(node, impulse / total);
    patch.centre += impulse / total * body.state().position(node);
  }
  return patch;
}

double ContactStiffness::normalStiffness(FemBody& body, const ContactPatch& patch,
                                         double tolerance) {
  const int n = body.model().nodeCount();
  const SystemOperator& system = body.stepper().system();
  const double dt = body.stepper().lastTimeStep();
  const double beta = body.model().material().stiffness_damping;
  if (!(dt > 0)) return 0;

  NodeConstraints constraints(n);
  for (const auto& group : body.groups()) {
    for (int node : group->nodes())
      constraints.prescribeVelocity(node, Eigen::Vector3d::Zero());
  }
  load_.setZero(3 * n);
  for (const auto& [node, w] : patch.load)
    load_.segment<3>(3 * node) = w * patch.normal;
  SolverSettings settings = body.stepper().settings();
  settings.tolerance = tolerance;
  Eigen::VectorXd& dv = warm_[&body];
  if (dv.size() != 3 * n) dv.setZero(3 * n);
  cg_.solve(system, constraints, load_, settings, dv);
  double compliance = 0;  // m/N
  for (const auto& [node, w] : patch.load)
    compliance += w * patch.normal.dot(dv.segment<3>(3 * node));
  compliance *= dt * dt + dt * beta;
  return compliance > 0 ? 1.0 / compliance : 0.0;
}

}  // namespace torsion::haptics
