// The FEM body's share of its contact island (docs/contact-solve.md, bullet/island_step.h): this
// step's detection as SAP rows; the answer written back where detection, the rigid partners'
// finish() and the checkpoints read it.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "torsion/bt_conversions.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/solve/convex_rows.h"
#include "torsion/contact/solve/face_contact_rows.h"
#include "torsion/contact/solve/node_contact_rows.h"
#include "torsion/contact/solve/rigid_contact_rows.h"
#include "torsion/contact/solve/rigid_joint_rows.h"
#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion {

namespace {

// Half the mean edge of the rest surface: a face row's lagged impulse follows its rigid feature
// within this (face_contact_rows.h), far enough for a step's slide, short of the next feature.
double featureMatchRadius(const TetMesh& mesh) {
  double sum = 0;
  int edges = 0;
  const std::vector<Eigen::Vector3d>& x = mesh.restPositions();
  for (const Triangle& t : mesh.surfaceTriangles()) {
    for (std::size_t k = 0; k < 3; ++k) {
      sum +=
          (x[static_cast<std::size_t>(t[k])] - x[static_cast<std::size_t>(t[(k + 1) % 3])]).norm();
      ++edges;
    }
  }
  return edges > 0 ? 0.5 * sum / edges : 0.0;
}

// The friction-bound group of each row: a node or face row's partner, and for each row between
// rigid bodies a group of its own, numbered after the partners.
std::vector<int> rowGroups(const sap::NodeContactIsland& island,
                           const std::vector<NodeContact>& contacts,
                           const std::vector<FaceContact>& faces, std::size_t partner_count) {
  std::vector<int> group(island.rows.size(), -1);
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    if (island.row_contact[r] >= 0) {
      group[r] = contacts[static_cast<std::size_t>(island.row_contact[r])].partner;
    } else if (r < island.row_face.size() && island.row_face[r] >= 0) {
      group[r] = faces[static_cast<std::size_t>(island.row_face[r])].partner;
    } else {
      group[r] = static_cast<int>(partner_count + r);
    }
  }
  return group;
}

// A dynamic partner's twist at the step's start: Bullet's, less Bullet's contact impulses that the
// island solves afresh and the impulse of the step's forces and torques (gravity included: still
// on the body while the FEM steps; Bullet clears them after the step).
Vector6d stepStartVelocity(const RigidPartner& k, double dt) {
  Vector6d impulse = k.bullet_contact_impulse;
  if (k.body != nullptr)
    impulse +=
        dt * (Vector6d() << toEigen(k.body->getTotalForce()), toEigen(k.body->getTotalTorque()))
                 .finished();
  return k.entry_velocity - partnerResponse(k, impulse);
}

// A row between rigid bodies (a contact point or a joint's row): not the FEM body's contact.
bool isRigidRow(const sap::NodeContactIsland& island, std::size_t r) {
  return (r < island.row_rigid.size() && island.row_rigid[r] >= 0) ||
         (r < island.row_joint.size() && island.row_joint[r] >= 0);
}

}  // namespace

bool RigidContactSolver::islandTakesRigidContacts(btRigidBody& body) const {
  btDispatcher* dispatcher = soft_body_->getWorldInfo()->m_dispatcher;
  if (dispatcher == nullptr) return false;
  return sap::gatherRigidContactGroup(
             *dispatcher, {&body},
             [this](const btCollisionObject& object) { return startPoseOf(object); },
             joints_ != nullptr ? joints_->joints() : std::vector<btTypedConstraint*>{})
      .contains(&body);
}

void RigidContactSolver::takeRigidContacts() {
  rigid_group_ = {};
  rigid_impulses_.clear();
  btDispatcher* dispatcher = soft_body_->getWorldInfo()->m_dispatcher;
  std::vector<btRigidBody*> seeds;
  for (const RigidPartner& k : partners_) {
    if (k.body != nullptr && k.link == nullptr && (k.dynamic || k.supported))
      seeds.push_back(k.body);
  }
  if (dispatcher == nullptr || seeds.empty()) return;
  const sap::StartPose start_pose = [this](const btCollisionObject& object) {
    return startPoseOf(object);
  };
  if (joints_ == nullptr) {
    rigid_group_ = sap::gatherRigidContactGroup(*dispatcher, seeds, start_pose, {});
  } else {
    rigid_group_ = sap::gatherRigidContactGroup(*dispatcher, seeds, start_pose, joints_->joints());
    sap::addJointRows(rigid_group_, *joints_, start_pose, dt_);
  }
  for (std::size_t b = 0; b < rigid_group_.bodies.size(); ++b) {
    RigidPartner& k = partners_[static_cast<std::size_t>(partnerIndex(rigid_group_.bodies[b]))];
    k.dynamic = true;
    k.supported = false;
    // Bullet's contact impulses on the body, and its joint impulses (joint_ledger.h): what the
    // island solves afresh.
    k.bullet_contact_impulse = rigid_group_.bullet_impulses[b];
    if (joints_ != nullptr)
      k.bullet_contact_impulse += joints_->jointImpulse(
          *rigid_group_.bodies[b], rigid_group_.bullet_impulses[b], k.mass_matrix, dt_);
  }
}

double RigidContactSolver::lookahead(double dt) const {
  return dt * (1 + sap::RowDefaults{}.dissipation_steps);
}

sap::ConvexRows RigidContactSolver::convexRows() {
  const sap::RowDefaults defaults;
  // Last step's normal impulses: the friction bounds of the lagged model.
  std::vector<sap::LaggedImpulse> lagged_nodes;
  for (std::size_t k = 0; k < previous_active_.size(); ++k) {
    const double gamma_n = previous_normal_[k].dot(previous_impulse_[k]);
    if (gamma_n > 0)
      lagged_nodes.push_back({previous_active_[k].first, previous_active_[k].second, gamma_n});
  }
  sap::ConvexRows rows;
  rows.island = sap::buildNodeContactIsland(contacts_, partners_, 0, lagged_nodes, defaults, dt_);
  rows.faces = sap::islandFaceContacts(*this);
  if (feature_match_radius_ < 0) feature_match_radius_ = featureMatchRadius(model_->mesh());
  sap::addFaceContactRows(rows.island, rows.faces, partners_, 0, lagged_features_,
                          feature_match_radius_, defaults, dt_);
  const sap::RigidContactGroup& group = rigid_group_;
  std::vector<int> group_body(group.bodies.size());
  for (std::size_t g = 0; g < group.bodies.size(); ++g)
    group_body[g] =
        rows.island.partner_body[static_cast<std::size_t>(partnerIndex(group.bodies[g]))];
  sap::addRigidContactRows(rows.island, group, group_body, defaults, dt_);
  sap::addRigidJointRows(rows.island, group, group_body);
  rows.row_group = rowGroups(rows.island, contacts_, rows.faces, partners_.size());
  rows.body_objects.assign(rows.island.rigid_bodies.size(), nullptr);
  rows.start_twists.assign(rows.island.rigid_bodies.size(), Vector6d::Zero());
  for (std::size_t k = 0; k < partners_.size(); ++k) {
    const int body = rows.island.partner_body[k];
    if (body < 1) continue;
    rows.body_objects[static_cast<std::size_t>(body - 1)] = partners_[k].object;
    // Warm start: each body's velocity at the step's start, as the FEM body's (the last step's
    // answer). Bullet's velocity carries the step's forces, gravity included, which the contacts
    // under a resting body cancel: started there, Newton's first directions went through the
    // contacts and were cut to a few percent by the line search (bullet_boxes: 23 Newton
    // iterations a step at rest, 12 from the step's start).
    rows.start_twists[static_cast<std::size_t>(body - 1)] = stepStartVelocity(partners_[k], dt_);
  }
  for (std::size_t r = 0; r < rows.island.rows.size(); ++r) {
    if (r < rows.island.row_rigid.size() && rows.island.row_rigid[r] >= 0) {
      rows.row_key.push_back(
          group.points[static_cast<std::size_t>(rows.island.row_rigid[r])].point);
      rows.row_key_index.push_back(0);
    } else if (r < rows.island.row_joint.size() && rows.island.row_joint[r] >= 0) {
      const auto j = static_cast<std::size_t>(rows.island.row_joint[r]);
      rows.row_key.push_back(group.joint_rows[j].joint);
      rows.row_key_index.push_back(static_cast<int>(j));
    } else {
      rows.row_key.push_back(nullptr);  // this body's own
      rows.row_key_index.push_back(0);
    }
  }
  return rows;
}

void RigidContactSolver::takeConvexSolution(const sap::ConvexRows& rows,
                                            const sap::SapReport& report,
                                            const std::vector<sap::SolvedBody>& bodies) {
  const sap::NodeContactIsland& island = rows.island;
  const std::vector<FaceContact>& faces = rows.faces;
  const sap::RigidContactGroup& group = rigid_group_;
  // The partners: every one's impulse (what finish() gives supported bodies and multibody links)
  // is the wrench of its rows; a dynamic one's twist is the island's (sap::SolvedBody).
  std::vector<Vector6d> impulses = sap::partnerImpulses(island, contacts_, partners_, report);
  sap::addFacePartnerImpulses(island, faces, report, impulses);
  for (std::size_t k = 0; k < partners_.size(); ++k) {
    partners_[k].impulse = impulses[k];
    const int body = island.partner_body[k];
    if (body < 1) continue;
    const sap::SolvedBody& solved = bodies[static_cast<std::size_t>(body - 1)];
    partners_[k].velocity = solved.twist;
    partners_[k].applied_by_another_body = !solved.applies;
  }
  // The rows' states and impulses, where detection's memory, the statistics and the checkpoints
  // read them.
  stats_.active = stats_.face_active = stats_.sticking = 0;
  stats_.normal_impulse = 0;
  stats_.max_end_penetration = 0;
  rigid_impulses_ = sap::rigidPointImpulses(island, group, report);  // for finish()
  joint_impulses_ = sap::jointRowImpulses(island, group, report);
  stats_.rigid_rows = static_cast<int>(group.points.size());
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    if (isRigidRow(island, r)) continue;  // between rigid bodies: not this body's contacts
    const Eigen::Vector3d& gamma = report.impulses[r];
    const double end_gap = island.rows[r].gap + dt_ * report.contact_velocities[r].z();
    stats_.max_end_penetration = std::max(stats_.max_end_penetration, -end_gap);
    const bool active = gamma.z() > 0;
    const bool stick = report.states[r] == sap::ContactState::kStick;
    if (active) {
      ++stats_.active;
      stats_.normal_impulse += gamma.z();
      if (stick) ++stats_.sticking;
      if (island.row_contact[r] < 0) ++stats_.face_active;
    }
    if (island.row_contact[r] < 0) continue;
    NodeContact& c = contacts_[static_cast<std::size_t>(island.row_contact[r])];
    c.impulse = island.rows[r].frame.transpose() * gamma;
    c.normal_impulse = gamma.z();
    if (c.anchored) continue;  // sticks for good, pulling or pushing
    c.state = !active ? NodeContact::State::kInactive
                      : (stick ? NodeContact::State::kStick : NodeContact::State::kSlide);
  }
  lagged_features_ = sap::laggedFaceImpulses(island, faces, partners_, report);
  solved_faces_ = faces;
  for (std::size_t r = 0; r < island.row_face.size(); ++r) {
    if (island.row_face[r] < 0) continue;
    FaceContact& f = solved_faces_[static_cast<std::size_t>(island.row_face[r])];
    const Eigen::Vector3d& gamma = report.impulses[r];
    f.impulse = island.rows[r].frame.transpose() * gamma;  // on the face
    f.state = !(gamma.z() > 0)                                ? FaceContact::State::kInactive
              : report.states[r] == sap::ContactState::kStick ? FaceContact::State::kStick
                                                              : FaceContact::State::kSlide;
  }
  stats_.newton_iterations = report.newton_iterations;
  stats_.converged = report.converged;
}

}  // namespace torsion
