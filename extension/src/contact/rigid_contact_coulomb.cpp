// The FEM-rigid contact solve in contact space (docs/contact.md, "Coulomb's law solved in contact
// space"): the step's system is factorised once (sparse Cholesky), condensed onto the contacts
// (the Delassus operator W = G A^-1 G^T plus the rigid partners' response), Coulomb's law is solved
// there for every contact at once (coulomb_problem.h), and the velocities follow from the impulses
// without another solve. Stick, slide and separation are then consistent with each other and with
// the impulses the step applies: no state is decided between solves.

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "torsion/contact/rigid_contact.h"

namespace torsion {

namespace {

// The 3x6 map from a partner's (v, omega) to the velocity of its point at lever r.
Eigen::Matrix<double, 3, 6> pointJacobian(const Eigen::Vector3d& r) {
  Eigen::Matrix<double, 3, 6> J;
  J << Eigen::Matrix3d::Identity(),
      (Eigen::Matrix3d() << 0, r.z(), -r.y(), -r.z(), 0, r.x(), r.y(), -r.x(), 0).finished();
  return J;
}

// Applies the node constraints' filter S to every column of `columns` (3n rows), in place.
void filterColumns(const NodeConstraints& constraints, Eigen::MatrixXd& columns) {
  Eigen::VectorXd column;
  for (Eigen::Index c = 0; c < columns.cols(); ++c) {
    column = columns.col(c);
    constraints.filter(column);
    columns.col(c) = column;
  }
}

}  // namespace

bool RigidContactSolver::solvesInContactSpace(const SystemOperator& op) const {
  // The factor holds M and K (and the volume barrier's blocks), not an added operator term: a body
  // in FEM-FEM contact (its pair penalties) keeps the active set.
  // Multibody links keep it too: an anchored light multibody pendulum blew up within 20 steps in
  // contact space (not yet understood; docs/contact.md).
  const bool touches_link = std::any_of(partners_.begin(), partners_.end(),
                                        [](const RigidPartner& k) { return k.link != nullptr; });
  return settings_.friction_solve == ContactSettings::FrictionSolve::kContactSpace &&
         op.addedTerm() == nullptr && !touches_link;
}

void RigidContactSolver::gatherCoulombRows() {
  rows_.clear();
  for (size_t c = 0; c < contacts_.size(); ++c) {
    const NodeContact& nc = contacts_[c];
    if (nc.held) continue;  // held nodes push by the sequential pass (rigid_contact_held.cpp)
    CoulombRow row;
    row.node_contact = static_cast<int>(c);
    row.nodes = {nc.node, -1, -1};
    row.weights = Eigen::Vector3d(1, 0, 0);
    row.partner = nc.partner;
    row.normal = nc.normal;
    row.lever = nc.lever;
    row.gap = nc.gap;
    row.friction = nc.friction;
    row.bilateral = nc.anchored;
    rows_.push_back(row);
  }
  const std::vector<FaceContact>& faces = faces_.contacts();
  for (size_t f = 0; f < faces.size(); ++f) {
    const FaceContact& fc = faces[f];
    CoulombRow row;
    row.face_contact = static_cast<int>(f);
    row.nodes = fc.nodes;
    row.weights = fc.weights;
    row.partner = fc.partner;
    row.normal = fc.normal;
    row.lever = fc.lever;
    row.gap = fc.gap;
    row.friction = fc.friction;
    rows_.push_back(row);
  }
}

LinearSolveReport RigidContactSolver::solveInContactSpace(const SystemOperator& op,
                                                          const NodeConstraints& constraints,
                                                          const Eigen::VectorXd& b,
                                                          Eigen::VectorXd& v) {
  LinearSolveReport report;
  report.relative_residual = std::numeric_limits<double>::infinity();
  const int n = model_->nodeCount();
  const double dt = dt_;
  for (RigidPartner& k : partners_)
    k.velocity = k.entry_velocity;

  // The free step: A v = b with the node groups' prescriptions, no contact.
  v_c_.setZero(3 * n);
  constraints.impose(v_c_);
  op.multiply(v_c_, product_);
  r_ = b - product_;
  constraints.filter(r_);
  const double reference = r_.norm();
  if (!std::isfinite(reference)) {
    report.breakdown = true;
    report.breakdown_reason = "the right-hand side or the matrix is not finite (overflow)";
    return report;
  }
  const Eigen::SparseMatrix<double>& A = factorisation_.assembler->assemble(op, constraints);
  if (!factorisation_.factor->factorize(A)) {
    report.breakdown = true;
    report.breakdown_reason = "the Cholesky factorisation failed (matrix not positive definite)";
    return report;
  }
  factorisation_.factor->solve(r_, scratch_);
  constraints.filter(scratch_);
  Eigen::VectorXd v_free = v_c_ + scratch_;

  // Contact space: each row's impulse r_i (on the soft side) moves the nodes by C_i r_i.
  gatherCoulombRows();
  const int m = static_cast<int>(rows_.size());
  // G^T, filtered (column j: the node forces of a unit impulse along row j's axis), kept as a
  // member so that a step does not allocate it anew.
  unit_impulses_.setZero(3 * n, 3 * m);
  for (int i = 0; i < m; ++i) {
    const CoulombRow& row = rows_[static_cast<size_t>(i)];
    for (size_t a = 0; a < 3; ++a) {
      if (row.nodes[a] < 0 || row.weights[static_cast<Eigen::Index>(a)] == 0) continue;
      unit_impulses_.block<3, 3>(3 * row.nodes[a], 3 * i) +=
          row.weights[static_cast<Eigen::Index>(a)] * Eigen::Matrix3d::Identity();
    }
  }
  filterColumns(constraints, unit_impulses_);
  factorisation_.factor->solve(unit_impulses_, responses_);
  filterColumns(constraints, responses_);

  CoulombProblem& problem = coulomb_;
  problem.delassus.setZero(3 * m, 3 * m);
  problem.free_velocity.setZero(3 * m);
  problem.normal.resize(static_cast<size_t>(m));
  problem.friction.resize(static_cast<size_t>(m));
  problem.bilateral.assign(static_cast<size_t>(m), 0);
  std::vector<Eigen::Matrix<double, 3, 6>> jacobians(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) {
    const CoulombRow& row = rows_[static_cast<size_t>(i)];
    const RigidPartner& k = partners_[static_cast<size_t>(row.partner)];
    Eigen::Vector3d soft = Eigen::Vector3d::Zero();
    for (size_t a = 0; a < 3; ++a) {
      if (row.nodes[a] < 0) continue;
      const double w = row.weights[static_cast<Eigen::Index>(a)];
      soft += w * v_free.segment<3>(3 * row.nodes[a]);
      problem.delassus.middleRows<3>(3 * i) += w * responses_.middleRows<3>(3 * row.nodes[a]);
    }
    problem.free_velocity.segment<3>(3 * i) =
        soft - pointVelocity(k.entry_velocity, row.lever) + row.normal * (row.gap / dt);
    problem.normal[static_cast<size_t>(i)] = row.normal;
    problem.friction[static_cast<size_t>(i)] = row.friction;
    problem.bilateral[static_cast<size_t>(i)] = row.bilateral ? 1 : 0;
    jacobians[static_cast<size_t>(i)] = pointJacobian(row.lever);
  }
  // A dynamic partner moves under every impulse on it: W_ij += J_i M^-1 J_j^T.
  for (int i = 0; i < m; ++i) {
    const RigidPartner& ki = partners_[static_cast<size_t>(rows_[static_cast<size_t>(i)].partner)];
    if (!ki.dynamic) continue;
    for (int j = 0; j < m; ++j) {
      if (rows_[static_cast<size_t>(j)].partner != rows_[static_cast<size_t>(i)].partner) continue;
      const Eigen::Matrix<double, 3, 6>& Jj = jacobians[static_cast<size_t>(j)];
      Eigen::Matrix<double, 6, 3> response;
      for (int a = 0; a < 3; ++a)
        response.col(a) = partnerResponse(ki, Jj.row(a).transpose());
      problem.delassus.block<3, 3>(3 * i, 3 * j) += jacobians[static_cast<size_t>(i)] * response;
    }
  }

  // Warm start: last step's impulses of the contacts found again.
  warmStartCoulomb();
  CoulombSettings cs;
  cs.tolerance = settings_.coulomb_tolerance;
  cs.acceptable = settings_.coulomb_acceptable;
  cs.max_sweeps = settings_.coulomb_max_sweeps;
  const CoulombReport solved = solveCoulomb(problem, cs, impulses_, contact_velocity_);
  stats_.coulomb_sweeps = solved.sweeps;
  stats_.coulomb_residual = solved.residual;

  // Velocities from the impulses.
  v = v_free + responses_ * impulses_;
  for (int i = 0; i < m; ++i) {
    const CoulombRow& row = rows_[static_cast<size_t>(i)];
    RigidPartner& k = partners_[static_cast<size_t>(row.partner)];
    if (!k.dynamic) continue;
    k.velocity -= partnerResponse(k, pointWrench(impulses_.segment<3>(3 * i), row.lever));
  }
  recordCoulombStates();

  // The honest residual of the result: S (A v - b - G^T r), relative to the larger of the free
  // right-hand side and the contact impulses (a body at rest held by its contacts has a
  // right-hand side of rounding size).
  op.multiply(v, product_);
  r_ = product_ - b;
  constraints.filter(r_);
  scratch_.noalias() = unit_impulses_ * impulses_;
  r_ -= scratch_;
  const double scale = std::max(reference, scratch_.norm());
  report.relative_residual = scale > 0 ? r_.norm() / scale : 0.0;
  report.iterations = solved.sweeps;
  if (!std::isfinite(report.relative_residual) || !v.allFinite()) {
    report.breakdown = true;
    report.breakdown_reason = "the contact solve's result is not finite";
    return report;
  }
  report.converged = report.relative_residual < 1e-6;
  ++stats_.active_set_iterations;
  stats_.active_set_converged = solved.converged;
  return report;
}

void RigidContactSolver::warmStartCoulomb() {
  const int m = static_cast<int>(rows_.size());
  impulses_.setZero(3 * m);
  for (int i = 0; i < m; ++i) {
    const CoulombRow& row = rows_[static_cast<size_t>(i)];
    if (row.face_contact >= 0) {
      impulses_.segment<3>(3 * i) =
          faces_.contacts()[static_cast<size_t>(row.face_contact)].multiplier;
      continue;
    }
    const NodeContact& c = contacts_[static_cast<size_t>(row.node_contact)];
    const btCollisionObject* object = partners_[static_cast<size_t>(c.partner)].object;
    for (size_t k = 0; k < previous_active_.size(); ++k) {
      if (previous_active_[k].first == c.node && previous_active_[k].second == object) {
        impulses_.segment<3>(3 * i) = previous_impulse_[k];
        break;
      }
    }
  }
}

void RigidContactSolver::recordCoulombStates() {
  // States as Coulomb's law classifies the solved impulses; node "constraint impulses" in
  // product_ as collectImpulses() reads them (the friction of a sliding contact apart).
  const int n = model_->nodeCount();
  product_.setZero(3 * n);
  std::vector<FaceContact>& faces = faces_.mutableContacts();
  for (size_t i = 0; i < rows_.size(); ++i) {
    const CoulombRow& row = rows_[i];
    const Eigen::Vector3d r = impulses_.segment<3>(3 * static_cast<Eigen::Index>(i));
    const double rn = row.normal.dot(r);
    const Eigen::Vector3d rt = r - row.normal * rn;
    const bool active = row.bilateral || rn > 0;
    const bool sliding =
        active && !row.bilateral && rt.norm() >= row.friction * rn * (1 - 1e-9) && rt.norm() > 0;
    if (row.face_contact >= 0) {
      FaceContact& f = faces[static_cast<size_t>(row.face_contact)];
      f.determined = false;
      f.multiplier = r;
      f.impulse = r;
      f.state = !active   ? FaceContact::State::kInactive
                : sliding ? FaceContact::State::kSlide
                          : FaceContact::State::kStick;
      continue;
    }
    NodeContact& c = contacts_[static_cast<size_t>(row.node_contact)];
    c.state = !active   ? NodeContact::State::kInactive
              : sliding ? NodeContact::State::kSlide
                        : NodeContact::State::kStick;
    c.friction_impulse = sliding ? rt : Eigen::Vector3d::Zero();
    product_.segment<3>(3 * c.node) = r - c.friction_impulse;
  }
}

}  // namespace torsion
