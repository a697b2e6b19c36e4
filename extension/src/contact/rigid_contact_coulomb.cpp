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

bool RigidContactSolver::solvesInContactSpace(const SystemOperator& op) const {
  // The factor holds M and K (and the volume barrier's blocks), not an added operator term: a body
  // in FEM-FEM contact (its pair penalties) keeps the active set.
  if (op.addedTerm() != nullptr) return false;
  switch (settings_.friction_solve) {
    case ContactSettings::FrictionSolve::kActiveSet:
      return false;
    case ContactSettings::FrictionSolve::kContactSpace:
      return true;
    case ContactSettings::FrictionSolve::kConvex:  // solveConvex, never here
      return false;
    case ContactSettings::FrictionSolve::kAuto:
      break;
  }
  // A dynamic partner's contacts share its six velocities: what one contact's stick or slide
  // does moves all the others, which the active set's rules decide one contact at a time and
  // contact space decides together. Nodes on static or kinematic geometry (partners_ holds this
  // step's touched partners only) each meet a prescribed motion, where the rules are right and
  // no factorisation is paid for.
  return std::any_of(partners_.begin(), partners_.end(),
                     [](const RigidPartner& k) { return k.dynamic; });
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
  // A face point that sits on one of its triangle's nodes (that node's weight at least
  // kFaceOnNode) while that node is a row against the same partner adds a second, slightly
  // tilted copy of the node's constraint: the pair makes W nearly singular and the solve stalls
  // (measured: a box resting on a tet10 slab, 52 such face points at the box's edges, residual
  // stuck near 1e-5 m/s). The node's row holds that point. (A node touching two partners keeps
  // its last row here: a face point on it may then stay a row, which is only the former cost.)
  std::vector<int>& node_row = node_row_;
  node_row.assign(static_cast<size_t>(model_->nodeCount()), -1);
  for (size_t i = 0; i < rows_.size(); ++i)
    node_row[static_cast<size_t>(rows_[i].nodes[0])] = static_cast<int>(i);
  const std::vector<FaceContact>& faces = faces_.contacts();
  for (size_t f = 0; f < faces.size(); ++f) {
    const FaceContact& fc = faces[f];
    Eigen::Index on = 0;
    if (fc.weights.maxCoeff(&on) >= kFaceOnNode) {
      const int i = node_row[static_cast<size_t>(fc.nodes[static_cast<size_t>(on)])];
      if (i >= 0 && rows_[static_cast<size_t>(i)].partner == fc.partner &&
          rows_[static_cast<size_t>(i)].normal.dot(fc.normal) > 0.99)
        continue;
    }
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
  if (!factoriseContactSystem(A)) {
    report.breakdown = true;
    report.breakdown_reason = "the Cholesky factorisation failed (matrix not positive definite)";
    return report;
  }
  scratch_ = factorisation_.factor->solve(r_);
  constraints.filter(scratch_);
  v_free_ = v_c_ + scratch_;

  // Every contact found is a row; the problem holds those that can push this step: closing
  // under the free motion, pushing last step, or bilateral. A row left out keeps a zero impulse,
  // which is Coulomb's law for it as long as its gap stays open at the end of the step; the rows
  // that the solved motion closes join and the problem is solved again. (A ball falling onto
  // the ground has all its surface nodes as rows, and a few of them touch.)
  gatherCoulombRows();
  warmStartCoulomb();
  const int all = static_cast<int>(rows_.size());
  selected_.clear();
  for (int i = 0; i < all; ++i) {
    const CoulombRow& row = rows_[static_cast<size_t>(i)];
    const bool pushed = impulses_.segment<3>(3 * i).squaredNorm() > 0;
    if (row.bilateral || pushed ||
        normalVelocity(row, v_free_, partners_[static_cast<size_t>(row.partner)].entry_velocity) *
                dt <
            settings_.activation_tolerance)
      selected_.push_back(i);
  }
  const Eigen::VectorXd warm = impulses_;
  CoulombReport solved;
  for (int round = 0;; ++round) {
    solved = solveSelectedRows(constraints, warm, v);
    // Rows left out that the solved motion drives into the surface join the problem.
    std::vector<int> joining;
    for (int i = 0; i < all; ++i) {
      if (std::binary_search(selected_.begin(), selected_.end(), i)) continue;  // sorted
      const CoulombRow& row = rows_[static_cast<size_t>(i)];
      const RigidPartner& k = partners_[static_cast<size_t>(row.partner)];
      if (normalVelocity(row, v, k.velocity) < -settings_.coulomb_tolerance) joining.push_back(i);
    }
    if (joining.empty() || round == kMaxRowRounds) break;
    selected_.insert(selected_.end(), joining.begin(), joining.end());
    std::sort(selected_.begin(), selected_.end());
  }
  stats_.coulomb_sweeps = solved.sweeps;
  stats_.coulomb_residual = solved.residual;
  if (!solved.converged && settings_.coulomb_fallback) {
    stats_.coulomb_fell_back = true;  // solve() takes the active set; contacts_ are untouched
    return report;
  }
  recordCoulombStates();

  // The honest residual of the result: S (A v - b - G^T r), relative to the larger of the free
  // right-hand side and the contact impulses (a body at rest held by its contacts has a
  // right-hand side of rounding size).
  // (scratch_, not product_: product_ holds the node impulses collectImpulses() reads, and with
  // them what a supported partner receives.)
  op.multiply(v, scratch_);
  r_ = scratch_ - b - contact_forces_;
  constraints.filter(r_);
  const double scale = std::max(reference, contact_forces_.norm());
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

double RigidContactSolver::normalVelocity(const CoulombRow& row, const Eigen::VectorXd& v,
                                          const Eigen::Matrix<double, 6, 1>& rigid) const {
  // The row's end gap rate n.(v_soft - v_rigid) + gap / dt: negative when the step ends inside.
  Eigen::Vector3d soft = Eigen::Vector3d::Zero();
  for (size_t a = 0; a < 3; ++a) {
    if (row.nodes[a] < 0) continue;
    soft += row.weights[static_cast<Eigen::Index>(a)] * v.segment<3>(3 * row.nodes[a]);
  }
  return row.normal.dot(soft - pointVelocity(rigid, row.lever)) + row.gap / dt_;
}

CoulombReport RigidContactSolver::solveSelectedRows(const NodeConstraints& constraints,
                                                    const Eigen::VectorXd& warm,
                                                    Eigen::VectorXd& v) {
  const double dt = dt_;
  const int m = static_cast<int>(selected_.size());
  for (RigidPartner& k : partners_)
    k.velocity = k.entry_velocity;
  buildUnitImpulses(constraints);
  // W_soft = (S G^T)^T A^-1 (S G^T) = B^T B with B = L^-1 P S G^T (P A P^T = L L^T): sparse
  // forward substitutions, each reaching only the factor's rows above the row's nodes in the
  // elimination tree, instead of two solves of the whole system per column
  // (delassus_condensation.h).
  CoulombProblem& problem = coulomb_;
  condensation_.lowerGram(factorisation_.factor->matrixL().nestedExpression(),
                          factorisation_.factor->permutationP().indices(), unit_impulses_,
                          problem.delassus);
  if (m > 0)
    problem.delassus.triangularView<Eigen::StrictlyUpper>() =
        problem.delassus.transpose().triangularView<Eigen::StrictlyUpper>();
  problem.free_velocity.setZero(3 * m);
  problem.normal.resize(static_cast<size_t>(m));
  problem.friction.resize(static_cast<size_t>(m));
  problem.bilateral.assign(static_cast<size_t>(m), 0);
  Eigen::VectorXd start(3 * m);
  std::vector<Eigen::Matrix<double, 3, 6>> jacobians(static_cast<size_t>(m));
  for (int s = 0; s < m; ++s) {
    const int i = selected_[static_cast<size_t>(s)];
    const CoulombRow& row = rows_[static_cast<size_t>(i)];
    const RigidPartner& k = partners_[static_cast<size_t>(row.partner)];
    Eigen::Vector3d soft = Eigen::Vector3d::Zero();
    for (size_t a = 0; a < 3; ++a) {
      if (row.nodes[a] < 0) continue;
      soft += row.weights[static_cast<Eigen::Index>(a)] * v_free_.segment<3>(3 * row.nodes[a]);
    }
    problem.free_velocity.segment<3>(3 * s) =
        soft - pointVelocity(k.entry_velocity, row.lever) + row.normal * (row.gap / dt);
    problem.normal[static_cast<size_t>(s)] = row.normal;
    problem.friction[static_cast<size_t>(s)] = row.friction;
    problem.bilateral[static_cast<size_t>(s)] = row.bilateral ? 1 : 0;
    jacobians[static_cast<size_t>(s)] = pointJacobian(row.lever);
    start.segment<3>(3 * s) = warm.segment<3>(3 * i);
  }
  // A dynamic partner moves under every impulse on it: W_ij += J_i M^-1 J_j^T.
  for (int s = 0; s < m; ++s) {
    const int partner = rows_[static_cast<size_t>(selected_[static_cast<size_t>(s)])].partner;
    const RigidPartner& k = partners_[static_cast<size_t>(partner)];
    if (!k.dynamic) continue;
    for (int t = 0; t < m; ++t) {
      if (rows_[static_cast<size_t>(selected_[static_cast<size_t>(t)])].partner != partner)
        continue;
      const Eigen::Matrix<double, 3, 6>& Jt = jacobians[static_cast<size_t>(t)];
      Eigen::Matrix<double, 6, 3> response;
      for (int a = 0; a < 3; ++a)
        response.col(a) = partnerResponse(k, Jt.row(a).transpose());
      problem.delassus.block<3, 3>(3 * s, 3 * t) += jacobians[static_cast<size_t>(s)] * response;
    }
  }

  // A contact compliance (constraint force mixing): every contact yields by coulomb_compliance
  // times W's largest diagonal entry per unit impulse. W is otherwise nearly singular where
  // contacts constrain the same motion (a rigid box on a stiff slab: its rank-6 response plus a
  // compliance 10^-10 of it, so the split of its load between the contacts is barely determined),
  // and the sweeps and Newton steps crawled there (a box sliding at up to 1.8 m/s over a coarse
  // stiff slab: a third of its steps ended at 1e-6 to 1e-5 m/s after 3000 sweeps). With it W is
  // definite, the Newton steps use it exactly, and those steps converge in a few.
  if (m > 0 && settings_.coulomb_compliance > 0)
    problem.delassus.diagonal().array() +=
        settings_.coulomb_compliance * problem.delassus.diagonal().maxCoeff();
  CoulombSettings cs;
  if (settings_.coulomb_compliance > 0) cs.newton_regularization = 0;
  cs.tolerance = settings_.coulomb_tolerance;
  cs.acceptable = settings_.coulomb_acceptable;
  cs.max_sweeps = settings_.coulomb_max_sweeps;
  CoulombReport solved = solveCoulomb(problem, cs, start, contact_velocity_);
  if (!solved.converged) {
    // Once more from no impulse at all: a warm start carried over from a step whose contacts
    // slid differently can hold the sweeps and Newton steps near a wrong corner of the cones
    // (measured: a box sliding over a coarse slab, 23 unconverged steps of 50, 7 converged from
    // cold). The better of the two is kept.
    cold_start_.setZero(3 * m);
    const CoulombReport again = solveCoulomb(problem, cs, cold_start_, cold_velocity_);
    if (again.residual < solved.residual) {
      solved = again;
      start.swap(cold_start_);
      contact_velocity_.swap(cold_velocity_);
    }
  }
  // Every row's impulse (zero for those left out), and the velocities they give: one more solve,
  // with the contacts' node forces S G^T r.
  impulses_.setZero(3 * static_cast<Eigen::Index>(rows_.size()));
  for (int s = 0; s < m; ++s)
    impulses_.segment<3>(3 * selected_[static_cast<size_t>(s)]) = start.segment<3>(3 * s);
  contact_forces_ = unit_impulses_ * start;
  scratch_ = factorisation_.factor->solve(contact_forces_);
  constraints.filter(scratch_);
  v = v_free_ + scratch_;
  for (int s = 0; s < m; ++s) {
    const CoulombRow& row = rows_[static_cast<size_t>(selected_[static_cast<size_t>(s)])];
    RigidPartner& k = partners_[static_cast<size_t>(row.partner)];
    if (!k.dynamic) continue;
    k.velocity -= partnerResponse(k, pointWrench(start.segment<3>(3 * s), row.lever));
  }
  return solved;
}

bool RigidContactSolver::factoriseContactSystem(const Eigen::SparseMatrix<double>& lower) {
  if (!Eigen::Map<const Eigen::VectorXd>(lower.valuePtr(), lower.nonZeros()).allFinite())
    return false;
  FactorWorkspace& f = factorisation_;
  if (f.rows != lower.rows() || f.entries != lower.nonZeros()) {
    f.factor->analyzePattern(lower);
    f.rows = lower.rows();
    f.entries = lower.nonZeros();
  }
  f.factor->factorize(lower);
  return f.factor->info() == Eigen::Success;
}

void RigidContactSolver::buildUnitImpulses(const NodeConstraints& constraints) {
  // Column 3s + a: the node forces S G_i^T e_a of a unit impulse along axis a of the s-th selected
  // row i (the weights of a face point spread it over the triangle's nodes; S leaves the free
  // components).
  const int n = model_->nodeCount();
  std::vector<Eigen::Triplet<double>> entries;
  entries.reserve(27 * selected_.size());
  for (size_t i = 0; i < selected_.size(); ++i) {
    const CoulombRow& row = rows_[static_cast<size_t>(selected_[i])];
    for (size_t a = 0; a < 3; ++a) {
      const int node = row.nodes[a];
      const double w = row.weights[static_cast<Eigen::Index>(a)];
      if (node < 0 || w == 0) continue;
      for (int axis = 0; axis < 3; ++axis) {
        const Eigen::Vector3d column =
            constraints.filterNode(node, w * Eigen::Vector3d::Unit(axis));
        for (int d = 0; d < 3; ++d) {
          if (column[d] != 0)
            entries.emplace_back(3 * node + d, 3 * static_cast<int>(i) + axis, column[d]);
        }
      }
    }
  }
  unit_impulses_.resize(3 * n, 3 * static_cast<Eigen::Index>(selected_.size()));
  unit_impulses_.setFromTriplets(entries.begin(), entries.end());
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
    const int k = previous_of_node_[static_cast<size_t>(c.node)];
    if (k >= 0 && previous_active_[static_cast<size_t>(k)].second == object)
      impulses_.segment<3>(3 * i) = previous_impulse_[static_cast<size_t>(k)];
  }
}

void RigidContactSolver::recordCoulombStates() {
  // States as Coulomb's law classifies the solved impulses; node "constraint impulses" in
  // product_ as collectImpulses() reads them (the friction of a sliding contact apart).
  const int n = model_->nodeCount();
  product_.setZero(3 * n);
  std::vector<FaceContact>& faces = faces_.mutableContacts();
  for (FaceContact& f : faces) {  // a face left out of the rows (on a node's row) does not push
    f.determined = false;
    f.multiplier.setZero();
    f.impulse.setZero();
    f.state = FaceContact::State::kInactive;
  }
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
