// The FEM-rigid contact step (docs/contact.md, "Pipeline, per step"): candidates from Bullet's
// broadphase, the narrow phase (rigid_contact_detection.cpp), the linear solve with the active
// set (rigid_contact_reduced_system.cpp, rigid_contact_active_set.cpp, rigid_contact_held.cpp,
// face_contacts.cpp), and the rigid bodies' new velocities. detect and solve read as the list of
// their stages.

#include "torsion/contact/rigid_contact.h"

#include <LinearMath/btTransformUtil.h>

#include <algorithm>
#include <cmath>

#include "torsion/bt_conversions.h"
#include "torsion/contact/solve/rigid_contact_rows.h"
#include "torsion/contact/solve/rigid_joint_rows.h"

namespace torsion {

const char* frictionSolveName(ContactSettings::FrictionSolve solve) {
  switch (solve) {
    case ContactSettings::FrictionSolve::kActiveSet:
      return "active_set";
    case ContactSettings::FrictionSolve::kContactSpace:
      return "contact_space";
    case ContactSettings::FrictionSolve::kConvex:
      return "convex";
    case ContactSettings::FrictionSolve::kAuto:
      break;
  }
  return "auto";
}

std::optional<ContactSettings::FrictionSolve> frictionSolveFromName(const std::string& name) {
  for (ContactSettings::FrictionSolve solve :
       {ContactSettings::FrictionSolve::kAuto, ContactSettings::FrictionSolve::kActiveSet,
        ContactSettings::FrictionSolve::kContactSpace, ContactSettings::FrictionSolve::kConvex}) {
    if (name == frictionSolveName(solve)) return solve;
  }
  return std::nullopt;
}

namespace {

// m/s: a body whose contacts all slid in the last step is sliding over the surface if it slips
// faster than this over the nodes it reaches.
constexpr double kSlidingSpeed = 0.01;

// Clears RigidPartner::sliding of the bodies that slip slower than kSlidingSpeed over the surface
// nodes they reach this step, at their velocity at the end of the last step (Bullet's, less this
// step's gravity; `state` at the start of the step). A body landing on a slope or resting on it
// slips by Poisson's effect and partial slip at its edges: taken as sliding, its new contacts
// started sliding and it crept (7 mm in 1 s 1 deg below the friction angle on a stiff slab).
void keepFastSliders(const std::vector<NodeContact>& contacts, const FemState& state, double dt,
                     std::vector<RigidPartner>& partners) {
  std::vector<double> fastest(partners.size(), 0.0);
  for (const NodeContact& c : contacts) {
    if (c.held) continue;
    const RigidPartner& k = partners[static_cast<size_t>(c.partner)];
    Vector6d last = k.entry_velocity;
    if (k.body != nullptr) last.head<3>() -= dt * toEigen(k.body->getGravity());
    double& f = fastest[static_cast<size_t>(c.partner)];
    f = std::max(f, tangentialSlip(c, state.velocity(c.node), last).norm());
  }
  for (size_t k = 0; k < partners.size(); ++k)
    partners[k].sliding = partners[k].sliding && fastest[k] > kSlidingSpeed;
}

}  // namespace

RigidContactSolver::RigidContactSolver(std::shared_ptr<const FemModel> model, btSoftBody* soft_body)
    : model_(std::move(model)), soft_body_(soft_body), faces_(model_->mesh()) {
  const int n = model_->nodeCount();
  surface_.assign(static_cast<size_t>(n), 0);
  for (const Triangle& tri : model_->mesh().surfaceTriangles()) {
    for (int a = 0; a < 3; ++a)
      surface_[static_cast<size_t>(tri[static_cast<size_t>(a)])] = 1;
  }
  node_contact_.assign(static_cast<size_t>(n), -1);
}

void RigidContactSolver::beginStep(double /*dt*/) {
  candidates_.clear();
  links_.beginStep();
  recordAnchorStartPoses();
}

void RigidContactSolver::addCandidate(const btCollisionObject* object) {
  // A concave object reaches us once per overlapping triangle: keep it once.
  if (std::find(candidates_.begin(), candidates_.end(), object) == candidates_.end())
    candidates_.push_back(object);
  links_.recordStartPose(object);
}

bool RigidContactSolver::detect(const FemState& state, const NodeConstraints& constraints,
                                double dt, sap::JointLedger* joints) {
  joints_ = joints;
  rememberActiveContacts();
  forgetLastStep(dt);
  if (candidates_.empty() && anchors_.empty()) return false;
  findContacts(state, constraints, dt);
  addAnchorContacts(state, constraints);
  dropUntouchedPartners();
  takeRigidContacts();
  warmStartActiveSet();
  keepFastSliders(contacts_, state, dt_, partners_);
  recordDetectionStats();
  return !contacts_.empty() || !faces_.empty();
}

LinearSolveReport RigidContactSolver::solve(const SystemOperator& op,
                                            const NodeConstraints& constraints,
                                            const Eigen::VectorXd& b,
                                            const SolverSettings& settings, Eigen::VectorXd& v) {
  base_ = &constraints;
  if (settings_.friction_solve == ContactSettings::FrictionSolve::kConvex)
    return solveConvex(op, constraints, b, v);
  numberRigidUnknowns();
  stats_.coulomb_fell_back = false;
  stats_.in_contact_space = solvesInContactSpace(op);
  if (stats_.in_contact_space) {
    // A step whose Coulomb problem does not converge falls back to the active set: stopped early,
    // the sweeps leave near-stick contacts stuck (measured: a box on a stiff tet10 slab 1 deg
    // above the friction angle slid 5 % short), where the active set's states hold within 3 %.
    fallback_velocity_ = v;
    const LinearSolveReport r = solveInContactSpace(op, constraints, b, v);
    if (r.breakdown) return r;
    if (!stats_.coulomb_fell_back) {
      collectImpulses();
      solveHeld(v, dt_);
      measureEndGaps(v);
      return r;
    }
    v = fallback_velocity_;
    numberRigidUnknowns();
  }
  warmStart(v);
  setFacePenalties(op);
  LinearSolveReport total;
  bool converged_set = false;
  for (int iteration = 0; iteration < settings_.max_active_set_iterations; ++iteration) {
    markDeterminedFaces();
    assembleRightHandSide(op, b);
    projectWarmStart();
    buildPreconditioner(op);
    const LinearSolveReport r = conjugateGradient(op, reduced_rhs_, settings, q_);
    accumulate(r, total);
    recoverSolution(op, v);
    if (r.breakdown) break;
    measureFrictionShares();
    rememberSolvedStates();
    if (!updateContactStates(v)) {
      converged_set = true;
      break;
    }
  }
  stats_.active_set_converged = converged_set;
  // At the iteration cap the states were updated after the last solve: the impulses are those
  // of the states that solve used (a contact released in that last update had its impulse
  // applied, and a slide's friction was the one before the update).
  if (!converged_set && !total.breakdown) restoreSolvedStates();
  collectImpulses();
  solveHeld(v, dt_);
  measureEndGaps(v);
  return total;
}

void RigidContactSolver::setFacePenalties(const SystemOperator& op) {
  if (faces_.empty()) return;
  op.diagonalBlocks(block_inverse_);
  faces_.setPenalties(block_inverse_, settings_.face_penalty);
}

void RigidContactSolver::markDeterminedFaces() {
  // Face contacts whose nodes are all prescribed along their normal sit this solve out.
  faces_.markDetermined([&](int node, const Eigen::Vector3d& normal) {
    if (base_->kind(node) == NodeConstraints::Kind::kFull) return true;
    const int ci = node_contact_[static_cast<size_t>(node)];
    if (ci < 0) return false;
    const NodeContact& c = contacts_[static_cast<size_t>(ci)];
    return c.state == NodeContact::State::kStick ||
           (c.state == NodeContact::State::kSlide && std::abs(c.normal.dot(normal)) > 0.99);
  });
}

void RigidContactSolver::accumulate(const LinearSolveReport& r, LinearSolveReport& total) {
  total.iterations += r.iterations;
  total.relative_residual = r.relative_residual;
  total.converged = r.converged;
  total.breakdown = total.breakdown || r.breakdown;
  if (r.breakdown_reason != nullptr) total.breakdown_reason = r.breakdown_reason;
  ++stats_.active_set_iterations;
}

bool RigidContactSolver::updateContactStates(const Eigen::VectorXd& v) {
  // Both sets are updated, whatever the other's answer.
  const bool nodes_changed = updateActiveSet(v, product_, dt_);
  setSlipResistances(v);
  const bool faces_changed = faces_.update(v, partners_, dt_, settings_.activation_tolerance,
                                           settings_.face_gap_tolerance);
  return nodes_changed || faces_changed;
}

void RigidContactSolver::rememberSolvedStates() {
  solved_states_.resize(contacts_.size());
  for (size_t c = 0; c < contacts_.size(); ++c)
    solved_states_[c] = {contacts_[c].state, contacts_[c].friction_impulse};
  solved_face_states_ = faces_.states();
}

void RigidContactSolver::restoreSolvedStates() {
  for (size_t c = 0; c < contacts_.size() && c < solved_states_.size(); ++c) {
    contacts_[c].state = solved_states_[c].first;
    contacts_[c].friction_impulse = solved_states_[c].second;
  }
  faces_.restoreStates(solved_face_states_);
}

void RigidContactSolver::collectImpulses() {
  // Impulses, statistics, and what the rigid bodies receive, from this solve alone: a step may
  // solve several times (inside self-contact's loop, an island's sweeps), and only its last
  // solve's impulses are the step's (summed, they counted the contacts once per solve).
  stats_.active = stats_.face_active = stats_.sticking = 0;
  stats_.normal_impulse = 0;
  for (RigidPartner& k : partners_)
    k.impulse.setZero();
  for (NodeContact& c : contacts_) {
    if (c.held) continue;
    if (c.state == NodeContact::State::kInactive) {
      c.impulse.setZero();
      c.normal_impulse = 0;
      continue;
    }
    const Eigen::Vector3d pi = product_.segment<3>(3 * c.node);
    // A sliding node's constraint impulse is along the normal, but for its friction's resistance
    // to a slip across the friction (slip_resistance), which the solve put into pi.
    c.impulse =
        pi + (c.state == NodeContact::State::kSlide ? c.friction_impulse : Eigen::Vector3d::Zero());
    c.normal_impulse = c.normal.dot(c.impulse);
    RigidPartner& k = partners_[static_cast<size_t>(c.partner)];
    k.impulse -= pointWrench(c.impulse, c.lever);
    ++stats_.active;
    if (c.state == NodeContact::State::kStick) ++stats_.sticking;
    stats_.normal_impulse += std::max(0.0, c.normal_impulse);
  }
  for (const FaceContact& c : faces_.contacts()) {
    if (c.state == FaceContact::State::kInactive || c.determined) continue;
    partners_[static_cast<size_t>(c.partner)].impulse -= pointWrench(c.impulse, c.lever);
    ++stats_.active;
    ++stats_.face_active;
    stats_.normal_impulse += std::max(0.0, c.normal.dot(c.impulse));
  }
}

void RigidContactSolver::measureEndGaps(const Eigen::VectorXd& v) {
  // The linearised end-of-step gap of every contact, with the final velocities.
  stats_.max_end_penetration = 0;
  for (const NodeContact& c : contacts_) {
    const Eigen::Vector3d rigid =
        pointVelocity(partners_[static_cast<size_t>(c.partner)].velocity, c.lever);
    const double gap_end = c.gap + dt_ * c.normal.dot(v.segment<3>(3 * c.node) - rigid);
    stats_.max_end_penetration = std::max(stats_.max_end_penetration, -gap_end);
  }
  for (const FaceContact& c : faces_.contacts()) {
    stats_.max_end_penetration =
        std::max(stats_.max_end_penetration, -faces_.endGap(c, v, partners_, dt_));
  }
}

void RigidContactSolver::finish() {
  // The island's rigid impulses onto Bullet's points, which now carry them (rigid_contact_rows.h).
  sap::writeBackRigidImpulses(rigid_group_, rigid_impulses_);
  if (joints_ != nullptr) sap::writeBackJointImpulses(rigid_group_, joint_impulses_, *joints_, dt_);
  rigid_group_ = {};
  rigid_impulses_.clear();
  joint_impulses_.clear();
  joints_ = nullptr;
  links_.applyImpulses(partners_, dt_);
  for (RigidPartner& k : partners_) {
    if (k.link != nullptr) continue;
    if (k.supported && k.body != nullptr) {
      // Explicit: the impulse changes the velocity only; Bullet's rigid solver meets it next
      // step together with the body's other contacts (the ground), which alone it knows.
      k.body->applyCentralImpulse(toBt(k.impulse.head<3>()));
      k.body->applyTorqueImpulse(toBt(k.impulse.tail<3>()));
      k.body->activate();
      continue;
    }
    if (!k.dynamic || k.body == nullptr || k.applied_by_another_body) continue;
    if (k.velocity == k.entry_velocity) continue;
    // Bullet integrated the pose with entry_velocity; the step's velocity is `velocity`
    // (symplectic Euler with the contact impulse inside the step).
    const Vector6d dV = k.velocity - k.entry_velocity;
    btTransform corrected;
    btTransformUtil::integrateTransform(k.body->getCenterOfMassTransform(), toBt(dV.head<3>()),
                                        toBt(dV.tail<3>()), toBtScalar(dt_), corrected);
    k.body->setLinearVelocity(toBt(k.velocity.head<3>()));
    k.body->setAngularVelocity(toBt(k.velocity.tail<3>()));
    k.body->setCenterOfMassTransform(corrected);
    if (k.body->getMotionState() != nullptr) k.body->getMotionState()->setWorldTransform(corrected);
    k.body->activate();
  }
}

}  // namespace torsion
