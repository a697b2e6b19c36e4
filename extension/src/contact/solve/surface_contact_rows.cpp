#include "torsion/contact/solve/surface_contact_rows.h"

#include <algorithm>
#include <cstddef>

namespace torsion::sap {

int addSurfaceContactRows(std::vector<ContactRow>& rows, const SurfaceContactSet& set,
                          int node_count_a, int body_a, int body_b, const RowDefaults& defaults,
                          double dt) {
  const int first = static_cast<int>(rows.size());
  for (const SurfaceContact& c : set.contacts()) {
    ContactRow row;
    row.frame = contactFrame(c.normal);
    for (std::size_t k = 0; k < c.nodes.size(); ++k) {
      if (c.beta[k] == 0) continue;
      const int node = c.nodes[k];
      const bool on_a = node < node_count_a;
      row.terms.push_back(nodeTerm(on_a ? body_a : body_b, on_a ? node : node - node_count_a,
                                   c.beta[k], row.frame));
    }
    row.mu = c.friction;
    row.stiffness = defaults.stiffness;
    row.dissipation_time = defaults.dissipation_steps * dt;
    row.gap = c.gap - c.target_gap;
    row.lagged_normal_impulse = std::max(0.0, c.normal.dot(c.multiplier));
    rows.push_back(std::move(row));
  }
  return first;
}

void takeSurfaceContactImpulses(SurfaceContactSet& set, const SapProblem& problem,
                                const std::vector<int>& rows, const SapReport& report, double dt) {
  std::size_t k = 0;
  for (SurfaceContact& c : set.contacts()) {
    const int i = rows[k++];
    const auto r = static_cast<std::size_t>(i);
    const ContactRow& row = problem.row(i);
    const Eigen::Vector3d& gamma = report.impulses[r];
    c.multiplier = row.frame.transpose() * gamma;
    c.state = !(gamma.z() > 0)                           ? SurfaceContact::State::kInactive
              : report.states[r] == ContactState::kStick ? SurfaceContact::State::kStick
                                                         : SurfaceContact::State::kSlide;
    c.end_gap = row.gap + dt * report.contact_velocities[r].z();
  }
}

}  // namespace torsion::sap
