#include "torsion/contact/solve/node_contact_rows.h"

#include <algorithm>
#include <cstddef>

namespace torsion::sap {

namespace {

// The lagged impulses ordered by node (stably: among one node's, as given), so that each
// contact finds the first of its node and object by a binary search rather than a scan.
std::vector<std::size_t> byNode(const std::vector<LaggedImpulse>& lagged) {
  std::vector<std::size_t> order(lagged.size());
  for (std::size_t k = 0; k < order.size(); ++k)
    order[k] = k;
  std::stable_sort(order.begin(), order.end(), [&lagged](std::size_t a, std::size_t b) {
    return lagged[a].node < lagged[b].node;
  });
  return order;
}

double laggedFor(const std::vector<LaggedImpulse>& lagged, const std::vector<std::size_t>& order,
                 int node, const btCollisionObject* object) {
  auto it = std::lower_bound(order.begin(), order.end(), node,
                             [&lagged](std::size_t k, int n) { return lagged[k].node < n; });
  for (; it != order.end() && lagged[*it].node == node; ++it) {
    if (lagged[*it].object == object) return lagged[*it].normal_impulse;
  }
  return 0;
}

ContactRow makeRow(const NodeContact& c, const RigidPartner& k, int fem_body, int rigid_body,
                   const RowDefaults& defaults, double dt) {
  ContactRow row;
  row.frame = contactFrame(c.normal);
  row.terms.push_back(nodeTerm(fem_body, c.node, 1.0, row.frame));
  completeRigidSide(row, c.lever, k, rigid_body, c.friction, c.gap, defaults, dt);
  return row;
}

}  // namespace

void completeRigidSide(ContactRow& row, const Eigen::Vector3d& lever, const RigidPartner& partner,
                       int rigid_body, double friction, double gap, const RowDefaults& defaults,
                       double dt) {
  if (rigid_body >= 0) {
    row.terms.push_back(rigidPointTerm(rigid_body, lever, -1.0, row.frame));
  } else {
    row.velocity_offset = -(row.frame * pointVelocity(partner.velocity, lever));
  }
  row.mu = friction;
  row.stiffness = defaults.stiffness;
  row.dissipation_time = defaults.dissipation_steps * dt;
  row.gap = gap;
}

NodeContactIsland buildNodeContactIsland(const std::vector<NodeContact>& contacts,
                                         const std::vector<RigidPartner>& partners, int fem_body,
                                         const std::vector<LaggedImpulse>& lagged,
                                         const RowDefaults& defaults, double dt) {
  NodeContactIsland island;
  island.partner_body.assign(partners.size(), -1);
  const std::vector<std::size_t> lagged_order = byNode(lagged);
  for (std::size_t p = 0; p < partners.size(); ++p) {
    const RigidPartner& k = partners[p];
    if (!k.dynamic) continue;
    island.partner_body[p] = static_cast<int>(island.rigid_bodies.size()) + 1;
    const Eigen::VectorXd momentum =
        partnerMomentum(k, k.entry_velocity) - k.bullet_contact_impulse;
    if (k.link != nullptr) {
      island.rigid_bodies.push_back(std::make_unique<LinkBody>(k.mass_matrix, momentum));
    } else {
      island.rigid_bodies.push_back(std::make_unique<RigidBody>(k.mass, k.inertia, momentum));
    }
  }
  for (std::size_t i = 0; i < contacts.size(); ++i) {
    const NodeContact& c = contacts[i];
    const auto p = static_cast<std::size_t>(c.partner);
    // A held node against a prescribed partner: both sides' motions are given, the row has
    // nothing to act on (and no mobility, w = 0, to regularise its impulse with).
    if (c.held && island.partner_body[p] < 0) continue;
    ContactRow row = makeRow(c, partners[p], fem_body, island.partner_body[p], defaults, dt);
    if (c.anchored) {
      row.kind = RowKind::kAnchor;
      row.mu = 0;
    } else {
      row.lagged_normal_impulse = laggedFor(lagged, lagged_order, c.node, partners[p].object);
    }
    island.rows.push_back(std::move(row));
    island.row_contact.push_back(static_cast<int>(i));
  }
  return island;
}

std::vector<const IslandBody*> islandBodies(const IslandBody& fem,
                                            const NodeContactIsland& island) {
  std::vector<const IslandBody*> bodies{&fem};
  for (const auto& r : island.rigid_bodies)
    bodies.push_back(r.get());
  return bodies;
}

std::vector<Vector6d> partnerImpulses(const NodeContactIsland& island,
                                      const std::vector<NodeContact>& contacts,
                                      const std::vector<RigidPartner>& partners,
                                      const SapReport& report) {
  std::vector<Vector6d> impulses(partners.size(), Vector6d::Zero());
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    if (island.row_contact[r] < 0) continue;
    const NodeContact& c = contacts[static_cast<std::size_t>(island.row_contact[r])];
    const Eigen::Vector3d on_node = island.rows[r].frame.transpose() * report.impulses[r];
    impulses[static_cast<std::size_t>(c.partner)] += pointWrench(-on_node, c.lever);
  }
  return impulses;
}

std::vector<LaggedImpulse> laggedImpulses(const NodeContactIsland& island,
                                          const std::vector<NodeContact>& contacts,
                                          const std::vector<RigidPartner>& partners,
                                          const SapReport& report) {
  std::vector<LaggedImpulse> lagged;
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    const double gamma_n = report.impulses[r].z();
    if (island.row_contact[r] < 0 || !(gamma_n > 0)) continue;
    const NodeContact& c = contacts[static_cast<std::size_t>(island.row_contact[r])];
    lagged.push_back({c.node, partners[static_cast<std::size_t>(c.partner)].object, gamma_n});
  }
  return lagged;
}

}  // namespace torsion::sap
