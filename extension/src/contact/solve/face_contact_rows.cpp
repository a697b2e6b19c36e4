#include "torsion/contact/solve/face_contact_rows.h"

#include <cstddef>

#include "torsion/contact/query/feature_contacts.h"

namespace torsion::sap {

namespace {

// Each remembered impulse goes to the face contact of the same object whose lever is nearest,
// within match_radius: the total is conserved (two rows at one corner do not both take the
// corner's impulse, and two remembered rows of one feature add up in the row that takes it).
std::vector<double> transferLagged(const std::vector<FaceContact>& faces,
                                   const std::vector<RigidPartner>& partners,
                                   const std::vector<LaggedFaceImpulse>& lagged,
                                   double match_radius) {
  std::vector<double> impulses(faces.size(), 0.0);
  for (const LaggedFaceImpulse& l : lagged) {
    double nearest = match_radius;
    std::size_t taker = faces.size();
    for (std::size_t i = 0; i < faces.size(); ++i) {
      if (partners[static_cast<std::size_t>(faces[i].partner)].object != l.object) continue;
      const double d = (faces[i].lever - l.lever).norm();
      if (d <= nearest) {
        nearest = d;
        taker = i;
      }
    }
    if (taker < faces.size()) impulses[taker] += l.normal_impulse;
  }
  return impulses;
}

ContactRow makeFaceRow(const FaceContact& c, const RigidPartner& k, int fem_body, int rigid_body,
                       const RowDefaults& defaults, double dt) {
  ContactRow row;
  row.frame = contactFrame(c.normal);
  for (std::size_t j = 0; j < 3; ++j) {
    const double w = c.weights[static_cast<Eigen::Index>(j)];
    if (w > 0) row.terms.push_back(nodeTerm(fem_body, c.nodes[j], w, row.frame));
  }
  completeRigidSide(row, c.lever, k, rigid_body, c.friction, c.gap, defaults, dt);
  return row;
}

bool insideDisk(const ContactRow& row, const Eigen::Vector3d& gamma) {
  return gamma.head<2>().norm() < (1 - 1e-6) * row.mu * row.lagged_normal_impulse;
}

}  // namespace

std::vector<FaceContact> islandFaceContacts(const RigidContactSolver& contacts) {
  std::vector<FaceContact> faces = contacts.featureContacts();
  for (const FaceContact& c : contacts.faceContacts()) {
    const btCollisionObject* object =
        contacts.partners()[static_cast<std::size_t>(c.partner)].object;
    if (!hasPolyhedronFeatures(*object->getCollisionShape())) faces.push_back(c);
  }
  return faces;
}

void addFaceContactRows(NodeContactIsland& island, const std::vector<FaceContact>& faces,
                        const std::vector<RigidPartner>& partners, int fem_body,
                        const std::vector<LaggedFaceImpulse>& lagged, double match_radius,
                        const RowDefaults& defaults, double dt) {
  island.row_face.resize(island.rows.size(), -1);
  const std::vector<double> transferred = transferLagged(faces, partners, lagged, match_radius);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const FaceContact& c = faces[i];
    const auto p = static_cast<std::size_t>(c.partner);
    ContactRow row = makeFaceRow(c, partners[p], fem_body, island.partner_body[p], defaults, dt);
    row.lagged_normal_impulse = transferred[i];
    island.rows.push_back(std::move(row));
    island.row_contact.push_back(-1);
    island.row_face.push_back(static_cast<int>(i));
  }
}

void addFacePartnerImpulses(const NodeContactIsland& island, const std::vector<FaceContact>& faces,
                            const SapReport& report, std::vector<Vector6d>& impulses) {
  for (std::size_t r = 0; r < island.row_face.size(); ++r) {
    if (island.row_face[r] < 0) continue;
    const FaceContact& c = faces[static_cast<std::size_t>(island.row_face[r])];
    const Eigen::Vector3d on_face = island.rows[r].frame.transpose() * report.impulses[r];
    impulses[static_cast<std::size_t>(c.partner)] += pointWrench(-on_face, c.lever);
  }
}

std::vector<LaggedFaceImpulse> laggedFaceImpulses(const NodeContactIsland& island,
                                                  const std::vector<FaceContact>& faces,
                                                  const std::vector<RigidPartner>& partners,
                                                  const SapReport& report) {
  std::vector<LaggedFaceImpulse> lagged;
  for (std::size_t r = 0; r < island.row_face.size(); ++r) {
    const double gamma_n = report.impulses[r].z();
    if (island.row_face[r] < 0 || !(gamma_n > 0)) continue;
    const FaceContact& c = faces[static_cast<std::size_t>(island.row_face[r])];
    lagged.push_back({partners[static_cast<std::size_t>(c.partner)].object, c.lever, gamma_n});
  }
  return lagged;
}

CarriedContacts carriedContacts(const NodeContactIsland& island,
                                const std::vector<NodeContact>& contacts,
                                const std::vector<RigidPartner>& partners,
                                const SapReport& report) {
  CarriedContacts carried;
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    const Eigen::Vector3d& gamma = report.impulses[r];
    if (!(gamma.z() > 0)) continue;
    const ContactRow& row = island.rows[r];
    const bool stick = insideDisk(row, gamma);
    const Eigen::Vector3d impulse = row.frame.transpose() * gamma;
    if (island.row_contact[r] >= 0) {
      const NodeContact& c = contacts[static_cast<std::size_t>(island.row_contact[r])];
      carried.nodes.push_back({c.node, partners[static_cast<std::size_t>(c.partner)].object,
                               stick ? NodeContact::State::kStick : NodeContact::State::kSlide,
                               impulse, c.normal});
    }
  }
  return carried;
}

}  // namespace torsion::sap
