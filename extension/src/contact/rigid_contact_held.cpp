// Held nodes against dynamic rigid bodies (docs/contact.md, "Held nodes"): a node prescribed by a
// hand or a node group pushes the rigid body, never the other way round.

#include <vector>

#include "torsion/contact/rigid_contact.h"

namespace torsion {

void RigidContactSolver::solveHeld(const Eigen::VectorXd& v, double dt) {
  // Held nodes are kinematic: each pushes its dynamic partner away (projected Gauss-Seidel on
  // the rigid body alone, normal impulse >= 0, Coulomb friction), never the other way round.
  std::vector<int> held;
  for (size_t c = 0; c < contacts_.size(); ++c) {
    const RigidPartner& k = partners_[static_cast<size_t>(contacts_[c].partner)];
    if (contacts_[c].held && (k.dynamic || k.supported)) held.push_back(static_cast<int>(c));
  }
  if (held.empty()) return;
  std::vector<Eigen::Vector3d> accumulated(held.size(), Eigen::Vector3d::Zero());
  for (int sweep = 0; sweep < settings_.held_iterations; ++sweep) {
    for (size_t h = 0; h < held.size(); ++h) {
      NodeContact& c = contacts_[static_cast<size_t>(held[h])];
      RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
      const Eigen::Vector3d w = v.segment<3>(3 * c.node);
      auto response = [&](const Eigen::Vector3d& dir) {
        // dir . W dir: the rigid point's speed change along dir per unit impulse along dir.
        return dir.dot(pointVelocity(partnerResponse(k, pointWrench(dir, c.lever)), c.lever));
      };
      // Normal: n . J V <= n . w + gap/dt, i.e. the end gap >= 0.
      const double bound = c.normal.dot(w) + c.gap / dt;
      const double violation = c.normal.dot(pointVelocity(k.velocity, c.lever)) - bound;
      double& lambda = accumulated[h].x();
      const double lambda_new = std::max(0.0, lambda + violation / response(c.normal));
      const double d_lambda = lambda_new - lambda;
      lambda = lambda_new;
      const Eigen::Vector3d impulse_on_rigid = -c.normal * d_lambda;
      k.velocity += partnerResponse(k, pointWrench(impulse_on_rigid, c.lever));
      k.impulse += pointWrench(impulse_on_rigid, c.lever);
      c.impulse -= impulse_on_rigid;
      // Friction: remove the tangential slip within mu lambda.
      Eigen::Vector3d slip = pointVelocity(k.velocity, c.lever) - w;
      slip -= c.normal * c.normal.dot(slip);
      const double s = slip.norm();
      if (s > 0 && c.friction > 0) {
        const Eigen::Vector3d t = slip / s;
        Eigen::Vector3d tangential = c.impulse - c.normal * c.normal.dot(c.impulse);
        Eigen::Vector3d target = tangential + t * (s / response(t));  // on the node
        const double cap = c.friction * lambda;
        if (target.norm() > cap) target *= cap / target.norm();
        const Eigen::Vector3d change_on_rigid = -(target - tangential);
        k.velocity += partnerResponse(k, pointWrench(change_on_rigid, c.lever));
        k.impulse += pointWrench(change_on_rigid, c.lever);
        c.impulse -= change_on_rigid;
      }
      c.normal_impulse = c.normal.dot(c.impulse);
    }
  }
  for (size_t h = 0; h < held.size(); ++h) {
    const NodeContact& c = contacts_[static_cast<size_t>(held[h])];
    if (accumulated[h].x() > 0) {
      ++stats_.active;
      stats_.normal_impulse += std::max(0.0, c.normal_impulse);
    }
  }
}

}  // namespace torsion
