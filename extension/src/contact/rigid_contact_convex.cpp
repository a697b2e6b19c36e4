// The convex contact solve of one FEM body and its rigid partners (ContactSettings::FrictionSolve
// ::kConvex, docs/contact-solve.md): this step's detection as one SAP island, solved once; the
// answer written back where detection, the rigid partners' finish() and the checkpoints read it.

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "torsion/bt_conversions.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/solve/face_contact_rows.h"
#include "torsion/contact/solve/fem_island_body.h"
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

// A partner's rows whose last normal impulses (their friction bounds) and this solve's differ by
// more than this factor either way are solved again with this solve's. At 2 a box landing while
// it slid lost +7 % more than mu times its normal impulses (its impact decays over three steps,
// each braked by the one before); at 1.1, -0.4 %. At rest and in steady sliding the two agree.
constexpr double kLaggedMismatch = 1.1;
constexpr int kMaxFrictionBoundRounds = 2;
// A partner whose rows new to the solve (no lagged impulse: no friction) carried more than this
// share of its normal impulse is solved again with the impulses found, as a mismatch is. A box
// sliding over a slab meets new nodes and features at its leading edges every step; left without
// friction for their first step, they took up to 0.3 % off its friction, which the distance 1 deg
// above the friction angle magnifies 15.7 times: +8.7 % of Coulomb's on a soft tet10 slab, +5.3 %
// with this.
constexpr double kNewRowsShare = 0.01;

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

// The lagged model bounds each row's friction by mu times its last normal impulse. Where that
// impulse is far from the present one the bound is wrong for a step: a contact new to the solve
// has none (a box landing on a slope slides freely: +12 % of Coulomb's distance on the soft
// incline), and after an impact the bound is the impact's (a box landing while it slides is
// braked by mu times its impact for one more step). Where a partner's rows together carried a
// normal impulse outside [1/1.1, 1.1] times the one the solve gave them, each row's bound becomes
// the impulse just found, in the island's rows and in the problem (whose other data do not
// depend on it), and the island is solved again: a fixed point of mu gamma_n, reached for the
// partners that need it. So is a partner whose new rows carried more than kNewRowsShare of its
// normal impulse. Returns whether any bound changed.
bool matchFrictionBounds(sap::NodeContactIsland& island, sap::SapProblem& problem,
                         const std::vector<int>& row_partner, const sap::SapReport& report) {
  if (row_partner.empty()) return false;
  const auto groups =
      static_cast<std::size_t>(*std::max_element(row_partner.begin(), row_partner.end()) + 1);
  std::vector<double> lagged(groups, 0.0), solved(groups, 0.0), unbounded(groups, 0.0);
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    const auto k = static_cast<std::size_t>(row_partner[r]);
    const double gamma_n = std::max(0.0, report.impulses[r].z());
    lagged[k] += island.rows[r].lagged_normal_impulse;
    solved[k] += gamma_n;
    if (island.rows[r].lagged_normal_impulse == 0) unbounded[k] += gamma_n;
  }
  bool changed = false;
  for (std::size_t r = 0; r < island.rows.size(); ++r) {
    const auto k = static_cast<std::size_t>(row_partner[r]);
    const bool mismatched = lagged[k] * kLaggedMismatch < solved[k] ||
                            lagged[k] > kLaggedMismatch * solved[k] ||
                            unbounded[k] > kNewRowsShare * solved[k];
    if (!mismatched || island.rows[r].mu == 0 || island.rows[r].kind != sap::RowKind::kContact)
      continue;
    const double gamma_n = std::max(0.0, report.impulses[r].z());
    if (gamma_n != island.rows[r].lagged_normal_impulse) {
      island.rows[r].lagged_normal_impulse = gamma_n;
      problem.setLaggedNormalImpulse(static_cast<int>(r), gamma_n);  // >= 0 and finite
      changed = true;
    }
  }
  return changed;
}

}  // namespace

bool RigidContactSolver::islandTakesRigidContacts(btRigidBody& body) const {
  if (settings_.friction_solve != ContactSettings::FrictionSolve::kConvex) return false;
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
  if (settings_.friction_solve != ContactSettings::FrictionSolve::kConvex) return;
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
  if (settings_.friction_solve != ContactSettings::FrictionSolve::kConvex) return dt;
  return dt * (1 + sap::RowDefaults{}.dissipation_steps);
}

LinearSolveReport RigidContactSolver::solveConvex(const SystemOperator& op,
                                                  const NodeConstraints& constraints,
                                                  const Eigen::VectorXd& b, Eigen::VectorXd& v) {
  const sap::RowDefaults defaults;
  // Last step's normal impulses: the friction bounds of the lagged model.
  std::vector<sap::LaggedImpulse> lagged_nodes;
  for (std::size_t k = 0; k < previous_active_.size(); ++k) {
    const double gamma_n = previous_normal_[k].dot(previous_impulse_[k]);
    if (gamma_n > 0)
      lagged_nodes.push_back({previous_active_[k].first, previous_active_[k].second, gamma_n});
  }
  const sap::RigidContactGroup& group = rigid_group_;
  sap::NodeContactIsland island =
      sap::buildNodeContactIsland(contacts_, partners_, 0, lagged_nodes, defaults, dt_);
  const std::vector<FaceContact> faces = sap::islandFaceContacts(*this);
  if (feature_match_radius_ < 0) feature_match_radius_ = featureMatchRadius(model_->mesh());
  sap::addFaceContactRows(island, faces, partners_, 0, lagged_features_, feature_match_radius_,
                          defaults, dt_);
  std::vector<int> group_body(group.bodies.size());
  for (std::size_t g = 0; g < group.bodies.size(); ++g)
    group_body[g] = island.partner_body[static_cast<std::size_t>(partnerIndex(group.bodies[g]))];
  sap::addRigidContactRows(island, group, group_body, defaults, dt_);
  sap::addRigidJointRows(island, group, group_body);
  const sap::FemIslandBody fem(op, constraints, b);
  const std::vector<int> row_partner = rowGroups(island, contacts_, faces, partners_.size());
  Result<sap::SapProblem> created =
      sap::SapProblem::create(sap::islandBodies(fem, island), island.rows, dt_);
  if (!created) return brokenDown({}, "the contact rows do not form a valid problem");
  Eigen::VectorXd x(created.value().dofs());
  x.head(v.size()) = v;
  // Warm start: each body's velocity at the step's start, as the FEM body's (the last step's
  // answer). Bullet's velocity carries the step's forces, gravity included, which the contacts
  // under a resting body cancel: started there, Newton's first directions went through the
  // contacts and were cut to a few percent by the line search (bullet_boxes: 23 Newton
  // iterations a step at rest, 12 from the step's start).
  for (std::size_t k = 0; k < partners_.size(); ++k) {
    const int body = island.partner_body[k];
    if (body >= 0)
      x.segment<6>(created.value().bodyOffset(body)) = stepStartVelocity(partners_[k], dt_);
  }
  // One solver for the rounds: its workspace is sized once.
  sap::SapSolver solver;
  sap::SapReport report = solver.solve(created.value(), x);
  // Every round's iterations count: the statistics say what the step cost.
  int newton = report.newton_iterations;
  int cg = report.cg_iterations;
  for (int round = 0; round < kMaxFrictionBoundRounds && report.converged &&
                      matchFrictionBounds(island, created.value(), row_partner, report);
       ++round) {
    report = solver.solve(created.value(), x);  // from the last solution
    newton += report.newton_iterations;
    cg += report.cg_iterations;
  }
  const sap::SapProblem& problem = created.value();
  v = x.head(v.size());

  // The partners: every one's impulse (what finish() gives supported bodies and multibody links)
  // is the wrench of its rows. A dynamic one's twist is its momentum plus the wrench of every row
  // on it (the island's J^T gamma), divided by its mass: the island's twist to the solve's
  // tolerance, and its momentum balance with the impulses the contacts report exact (the
  // optimality criterion alone leaves a residual of 1e-6 of the momenta).
  std::vector<Vector6d> impulses = sap::partnerImpulses(island, contacts_, partners_, report);
  sap::addFacePartnerImpulses(island, faces, report, impulses);
  Eigen::VectorXd row_impulses = Eigen::VectorXd::Zero(problem.dofs());
  for (int i = 0; i < problem.rowCount(); ++i)
    problem.addRowTranspose(i, report.impulses[static_cast<std::size_t>(i)], row_impulses);
  for (std::size_t k = 0; k < partners_.size(); ++k) {
    partners_[k].impulse = impulses[k];
    const int body = island.partner_body[k];
    if (body < 0) continue;
    const sap::IslandBody& rigid = *island.rigid_bodies[static_cast<std::size_t>(body - 1)];
    const Vector6d momentum = rigid.momentum() + row_impulses.segment<6>(problem.bodyOffset(body));
    partners_[k].velocity = Matrix6d(rigid.diagonalBlock(0)).llt().solve(momentum);
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
    f.determined = false;
    f.state = !(gamma.z() > 0)                                ? FaceContact::State::kInactive
              : report.states[r] == sap::ContactState::kStick ? FaceContact::State::kStick
                                                              : FaceContact::State::kSlide;
  }
  stats_.active_set_iterations = newton;
  stats_.active_set_converged = report.converged;

  LinearSolveReport out;
  out.iterations = cg;
  out.converged = true;  // the linear solves inside Newton; the contact solve's own verdict is
                         // stats().active_set_converged
  return out;
}

}  // namespace torsion
