// The SAP problem of an island (sap_problem.h; Castro, Permenter, Han 2022).
#include "torsion/contact/solve/sap_problem.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

namespace torsion::sap {

namespace {

constexpr double kSapPi = 3.14159265358979323846;

// S (S D S + I - S)^{-1} S: the inverse of D on the free dofs of its block, zero on the rest.
// S D S + I - S is SPD for SPD D and a projector S, and equals D where every dof is free.
DiagonalBlock inverseOnFreeDofs(const DiagonalBlock& d, const DiagonalBlock& s) {
  const auto n = d.rows();
  const DiagonalBlock identity = DiagonalBlock::Identity(n, n);
  // A block without prescribed dofs (most of them): S = I, and the general form below gives
  // exactly this (products with I are exact).
  if (s == identity) return d.llt().solve(identity);
  const DiagonalBlock compressed = s * d * s + (identity - s);
  const DiagonalBlock inverse = compressed.llt().solve(identity);
  return s * inverse * s;
}

// y = M x for an N x K block, each row summed left to right: the order Eigen's product of the
// run-time-sized blocks sums in (and its fixed-size product does not, for 3 rows), so the
// results are bit for bit those of `block * x`, without the product's size dispatch.
template <int N, int K, typename Block>
inline void blockProduct(const Block& m, const double* x, double* y) {
  for (int i = 0; i < N; ++i) {
    double sum = m(i, 0) * x[0];
    for (int k = 1; k < K; ++k)
      sum += m(i, k) * x[k];
    y[i] = sum;
  }
}

// y += M^T f for a 3 x K block, each entry summed over the 3 rows in order (as `block^T * f`).
template <int K, typename Block>
inline void addTransposeProduct(const Block& m, const Eigen::Vector3d& f, double* y) {
  for (int k = 0; k < K; ++k) {
    double sum = m(0, k) * f(0);
    sum += m(1, k) * f(1);
    sum += m(2, k) * f(2);
    y[k] += sum;
  }
}

}  // namespace

const char* toString(ContactState state) {
  switch (state) {
    case ContactState::kStick:
      return "stick";
    case ContactState::kSlide:
      return "slide";
    case ContactState::kSeparated:
      return "separated";
  }
  return "?";
}

RowResponse projectImpulse(const RowModel& m, const Eigen::Vector3d& vc) {
  RowResponse out;
  if (m.kind == RowKind::kJoint) {
    // sap_problem.h: the impulse clamped to [lo, hi], its cost linear beyond the bounds.
    const double y = (m.v_hat - vc(2)) / m.rn;
    const double gamma = std::clamp(y, m.lower, m.upper);
    out.gamma(2) = gamma;
    if (gamma == y) {
      out.g(2, 2) = 1 / m.rn;
      out.cost = 0.5 * m.rn * y * y;
      out.state = ContactState::kStick;
    } else {
      out.cost = gamma * m.rn * (y - 0.5 * gamma);
      out.state = gamma == 0 ? ContactState::kSeparated : ContactState::kSlide;
    }
    return out;
  }
  if (m.kind == RowKind::kAnchor) {
    out.gamma = (Eigen::Vector3d(0, 0, m.v_hat) - vc) / m.rn;
    out.g = Eigen::Matrix3d::Identity() / m.rn;
    out.cost = 0.5 * m.rn * out.gamma.squaredNorm();
    out.state = ContactState::kStick;
    return out;
  }
  // The lagged model (sap_problem.h): the compliant normal law, friction on the disk of radius r.
  const double yn = (m.v_hat - vc(2)) / m.rn;
  if (yn > 0) {
    out.gamma(2) = yn;
    out.g(2, 2) = 1 / m.rn;
    out.cost = 0.5 * m.rn * yn * yn;
  }
  const Eigen::Vector2d yt = -vc.head<2>() / m.rt;
  const double yr = yt.norm();
  if (!(m.radius > 0)) {
    // No friction (mu = 0 or no lagged impulse): ell_t = 0. The state says whether it slips.
    const bool slips = yr > 0;
    out.state = yn > 0 ? (slips ? ContactState::kSlide : ContactState::kStick)
                       : ContactState::kSeparated;  // then gamma = 0 and G = 0
  } else if (yr <= m.radius) {
    out.state = ContactState::kStick;
    out.gamma.head<2>() = yt;
    out.g(0, 0) = out.g(1, 1) = 1 / m.rt;
    out.cost += 0.5 * m.rt * yt.squaredNorm();
  } else {
    // Here y_r > r > 0. G_tt = r / (y_r R_t) (I - t t^T); ell_t = r |v_t| - R_t r^2 / 2.
    out.state = ContactState::kSlide;
    const Eigen::Vector2d t = yt / yr;
    out.gamma.head<2>() = m.radius * t;
    out.g.topLeftCorner<2, 2>() =
        (m.radius / (yr * m.rt)) * (Eigen::Matrix2d::Identity() - t * t.transpose());
    out.cost += m.rt * m.radius * (yr - 0.5 * m.radius);
  }
  return out;
}

void addSlipCurvature(const RowModel& m, const Eigen::Vector3d& vc, Eigen::Matrix3d& g) {
  if (m.kind != RowKind::kContact || !(m.radius > 0)) return;
  const Eigen::Vector2d yt = -vc.head<2>() / m.rt;
  const double yr = yt.norm();
  if (!(yr > m.radius)) return;  // sticking: G is whole
  const Eigen::Vector2d t = yt / yr;
  g.topLeftCorner<2, 2>() += (m.radius / (yr * m.rt)) * t * t.transpose();
}

Result<SapProblem> SapProblem::create(std::vector<const IslandBody*> bodies,
                                      std::vector<ContactRow> rows, double dt,
                                      const SapParameters& parameters) {
  SapProblem p;
  const Status made = p.reset(std::move(bodies), std::move(rows), dt, parameters);
  if (!made) return made.error();
  return Result<SapProblem>(std::move(p));
}

void SapProblem::clear() {
  bodies_.clear();
  rows_.clear();
  models_.clear();
  body_offsets_.clear();
  block_starts_.clear();
  block_offsets_.clear();
  blocks_.clear();
  projectors_.clear();
  free_inverses_.clear();
  dofs_ = 0;
  dt_ = 0;
}

Status SapProblem::reset(std::vector<const IslandBody*> bodies, std::vector<ContactRow> rows,
                         double dt, const SapParameters& parameters) {
  clear();
  if (!(dt > 0)) return Error{"SAP problem: time step " + std::to_string(dt) + " is not > 0"};
  for (const IslandBody* body : bodies)
    if (body == nullptr) return Error{"SAP problem: a body is null"};
  bodies_ = std::move(bodies);
  for (const IslandBody* body : bodies_) {
    body_offsets_.push_back(dofs_);
    dofs_ += body->dofs();
  }
  collectBlocks();
  rows_ = std::move(rows);
  for (size_t i = 0; i < rows_.size(); ++i) {
    const Status status = validate(rows_[i]);
    if (!status) {
      const std::string message =
          "SAP problem: row " + std::to_string(i) + ": " + status.error().message;
      clear();
      return Error{message};
    }
  }
  dt_ = dt;
  for (const ContactRow& row : rows_)
    models_.push_back(makeModel(row, dt, parameters));
  return Ok{};
}

void SapProblem::collectBlocks() {
  momentum_.resize(dofs_);
  inverse_sqrt_diagonal_.resize(dofs_);
  // Sized once: an 8332-tet body has ~2000 blocks, and growing four vectors block by block cost
  // 8 % of a contact step (reallocation and first touch of each copy).
  std::size_t block_count = 0;
  for (const IslandBody* body : bodies_)
    block_count += static_cast<std::size_t>(body->dofs() / body->blockSize());
  blocks_.reserve(block_count);
  projectors_.reserve(block_count);
  free_inverses_.reserve(block_count);
  block_offsets_.reserve(block_count);
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const IslandBody& body = *bodies_[b];
    const int offset = body_offsets_[b];
    momentum_.segment(offset, body.dofs()) = body.momentum();
    block_starts_.push_back(static_cast<int>(blocks_.size()));
    for (int k = 0; k < body.dofs() / body.blockSize(); ++k) {
      blocks_.push_back(body.diagonalBlock(k));
      projectors_.push_back(body.freeProjector(k));
      block_offsets_.push_back(offset + k * body.blockSize());
      free_inverses_.push_back(inverseOnFreeDofs(blocks_.back(), projectors_.back()));
      inverse_sqrt_diagonal_.segment(block_offsets_.back(), body.blockSize()) =
          blocks_.back().diagonal().cwiseSqrt().cwiseInverse();
    }
  }
  block_starts_.push_back(static_cast<int>(blocks_.size()));
  body_in_.resize(bodies_.size());
  body_out_.resize(bodies_.size());
}

Status SapProblem::validate(const ContactRow& row) const {
  if (row.terms.empty()) return Error{"no terms"};
  if (row.kind == RowKind::kJoint) {
    if (!std::isfinite(row.target_velocity)) return Error{"joint target velocity is not finite"};
    if (!(row.lower <= 0) || !(row.upper >= 0))
      return Error{"joint impulse bounds [" + std::to_string(row.lower) + ", " +
                   std::to_string(row.upper) + "] do not hold 0"};
    if (!(row.relative_compliance >= 0) || !std::isfinite(row.relative_compliance))
      return Error{"joint compliance " + std::to_string(row.relative_compliance) +
                   " is not finite and >= 0"};
    return validateTerms(row);
  }
  if (!(row.mu >= 0)) return Error{"friction coefficient " + std::to_string(row.mu) + " < 0"};
  if (!(row.stiffness > 0)) return Error{"stiffness " + std::to_string(row.stiffness) + " <= 0"};
  if (!(row.dissipation_time >= 0))
    return Error{"dissipation time " + std::to_string(row.dissipation_time) + " < 0"};
  if (!std::isfinite(row.gap)) return Error{"gap is not finite"};
  if (!row.velocity_offset.allFinite()) return Error{"velocity offset is not finite"};
  if (!(row.lagged_normal_impulse >= 0) || !std::isfinite(row.lagged_normal_impulse))
    return Error{"lagged normal impulse " + std::to_string(row.lagged_normal_impulse) +
                 " is not finite and >= 0"};
  return validateTerms(row);
}

Status SapProblem::validateTerms(const ContactRow& row) const {
  for (const ContactTerm& term : row.terms) {
    if (term.body < 0 || term.body >= static_cast<int>(bodies_.size()))
      return Error{"term on body " + std::to_string(term.body) + ", which is not in the island"};
    const IslandBody& body = *bodies_[static_cast<size_t>(term.body)];
    const int size = body.blockSize();
    if (term.block.cols() != size || term.first_dof % size != 0 || term.first_dof < 0 ||
        term.first_dof + size > body.dofs())
      return Error{"term at dof " + std::to_string(term.first_dof) + " with " +
                   std::to_string(term.block.cols()) + " columns is not one block of its body"};
  }
  return Ok{};
}

int SapProblem::termBlock(const ContactTerm& term) const {
  const IslandBody& body = *bodies_[static_cast<size_t>(term.body)];
  return block_starts_[static_cast<size_t>(term.body)] + term.first_dof / body.blockSize();
}

RowModel SapProblem::makeModel(const ContactRow& row, double dt,
                               const SapParameters& parameters) const {
  // W_ii estimated term by term from the blocks the row acts on (sap_problem.h).
  Eigen::Matrix3d w_block = Eigen::Matrix3d::Zero();
  for (const ContactTerm& term : row.terms) {
    const auto k = static_cast<size_t>(termBlock(term));
    w_block += term.block * free_inverses_[k] * term.block.transpose();
  }
  RowModel m;
  m.kind = row.kind;
  if (row.kind == RowKind::kJoint) {
    // One-dimensional: w = W_nn, the target and bounds as given (sap_problem.h).
    m.w = w_block(2, 2);
    if (!(m.w > 0)) m.w = 1;  // on prescribed dofs alone: moves nothing, any w will do
    m.rn = std::max(parameters.joint_beta * parameters.joint_beta / (4 * kSapPi * kSapPi),
                    row.relative_compliance) *
           m.w;
    m.rt = parameters.sigma * m.w;
    m.v_hat = row.target_velocity;
    m.lower = row.lower;
    m.upper = row.upper;
    return m;
  }
  m.mu = row.mu;
  m.radius = row.mu * row.lagged_normal_impulse;
  const double rn_physical = 1 / (dt * (dt + row.dissipation_time) * row.stiffness);
  m.w = w_block.norm() / 3;
  // A row on prescribed dofs alone moves nothing; any positive w keeps its model well defined.
  if (!(m.w > 0)) m.w = rn_physical;
  m.rn = std::max(parameters.beta * parameters.beta / (4 * kSapPi * kSapPi) * m.w, rn_physical);
  m.rt = parameters.sigma * m.w;
  m.v_hat = -row.gap / (dt + row.dissipation_time);
  return m;
}

bool SapProblem::setLaggedNormalImpulse(int i, double impulse) {
  if (!(impulse >= 0) || !std::isfinite(impulse)) return false;
  const auto k = static_cast<size_t>(i);
  rows_[k].lagged_normal_impulse = impulse;
  models_[k].radius = rows_[k].mu * impulse;  // as makeModel
  return true;
}

bool SapProblem::setGap(int i, double gap) {
  const auto k = static_cast<size_t>(i);
  if (!std::isfinite(gap) || rows_[k].kind == RowKind::kJoint) return false;
  rows_[k].gap = gap;
  models_[k].v_hat = -gap / (dt_ + rows_[k].dissipation_time);  // as makeModel
  return true;
}

void SapProblem::multiplyA(const Eigen::VectorXd& x, Eigen::VectorXd& out) const {
  out.resize(dofs_);
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const int n = bodies_[b]->dofs();
    body_in_[b] = x.segment(body_offsets_[b], n);
    bodies_[b]->multiply(body_in_[b], body_out_[b]);
    out.segment(body_offsets_[b], n) = body_out_[b];
  }
}

Eigen::Vector3d SapProblem::rowVelocity(int i, const Eigen::VectorXd& v) const {
  return multiplyRow(i, v) + row(i).velocity_offset;
}

Eigen::Vector3d SapProblem::multiplyRow(int i, const Eigen::VectorXd& x) const {
  Eigen::Vector3d product = Eigen::Vector3d::Zero();
  // The two term widths as fixed-size products: the same sums in the same order as the
  // run-time-sized product, without its size dispatch.
  for (const ContactTerm& term : row(i).terms) {
    const int offset = termOffset(term);
    Eigen::Vector3d part;
    if (term.block.cols() == 3) {
      blockProduct<3, 3>(term.block, x.data() + offset, part.data());
      product += part;
    } else if (term.block.cols() == 6) {
      blockProduct<3, 6>(term.block, x.data() + offset, part.data());
      product += part;
    } else {
      product += term.block * x.segment(offset, term.block.cols());
    }
  }
  return product;
}

void SapProblem::addRowTranspose(int i, const Eigen::Vector3d& f, Eigen::VectorXd& out) const {
  for (const ContactTerm& term : row(i).terms) {
    const int offset = termOffset(term);
    if (term.block.cols() == 3) {
      addTransposeProduct<3>(term.block, f, out.data() + offset);
    } else if (term.block.cols() == 6) {
      addTransposeProduct<6>(term.block, f, out.data() + offset);
    } else {
      out.segment(offset, term.block.cols()) += term.block.transpose() * f;
    }
  }
}

void SapProblem::filter(Eigen::VectorXd& x) const {
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const int n = bodies_[b]->dofs();
    body_in_[b] = x.segment(body_offsets_[b], n);
    bodies_[b]->filter(body_in_[b]);
    x.segment(body_offsets_[b], n) = body_in_[b];
  }
}

void SapProblem::impose(Eigen::VectorXd& v) const {
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const int n = bodies_[b]->dofs();
    body_in_[b] = v.segment(body_offsets_[b], n);
    bodies_[b]->impose(body_in_[b]);
    v.segment(body_offsets_[b], n) = body_in_[b];
  }
}

void SapProblem::evaluate(const Eigen::VectorXd& v, SapEvaluation& e) const {
  multiplyA(v, e.av);
  evaluateWithAv(v, e);
}

void SapProblem::evaluate(const Eigen::VectorXd& v, Eigen::VectorXd&& av, SapEvaluation& e) const {
  e.av = std::move(av);  // swaps the storage: no allocation from one iterate to the next
  evaluateWithAv(v, e);
}

void SapProblem::evaluateWithAv(const Eigen::VectorXd& v, SapEvaluation& e) const {
  e.v = v;
  e.contact_impulse.setZero(dofs_);
  e.contact_velocity.resize(rows_.size());
  e.rows.resize(rows_.size());
  double contact_cost = 0;
  // Rows in their order, terms in theirs: the sums are the same for the same input.
  for (int i = 0; i < rowCount(); ++i) {
    const auto k = static_cast<size_t>(i);
    e.contact_velocity[k] = rowVelocity(i, v);
    e.rows[k] = projectImpulse(models_[k], e.contact_velocity[k]);
    addRowTranspose(i, e.rows[k].gamma, e.contact_impulse);
    contact_cost += e.rows[k].cost;
  }
  e.gradient = e.av - momentum_ - e.contact_impulse;
  filter(e.gradient);
  e.cost = 0.5 * v.dot(e.av) - momentum_.dot(v) + contact_cost;
}

void SapProblem::multiplyHessian(const SapEvaluation& e, const Eigen::VectorXd& x,
                                 Eigen::VectorXd& ax, Eigen::VectorXd& out) const {
  multiplyA(x, ax);
  out = ax;
  for (int i = 0; i < rowCount(); ++i) {
    const RowResponse& r = e.rows[static_cast<size_t>(i)];
    if (r.state == ContactState::kSeparated) continue;
    addRowTranspose(i, r.g * multiplyRow(i, x), out);
  }
  filter(out);
}

void SapProblem::preconditionerBlocks(std::vector<DiagonalBlock>& inverse) const {
  // Blocks of a body with its own preconditioner are not used (applyPreconditioner): left as A's.
  inverse.resize(blocks_.size());
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const bool own = bodies_[b]->hasPreconditioner();
    for (int k = block_starts_[b]; k < block_starts_[b + 1]; ++k) {
      const auto j = static_cast<size_t>(k);
      inverse[j] = own ? blocks_[j] : free_inverses_[j];
    }
  }
}

bool SapProblem::hasBodyPreconditioner() const {
  return std::any_of(bodies_.begin(), bodies_.end(),
                     [](const IslandBody* body) { return body->hasPreconditioner(); });
}

void SapProblem::applyPreconditioner(const std::vector<DiagonalBlock>& inverse,
                                     const Eigen::VectorXd& r, Eigen::VectorXd& out) const {
  out.resize(dofs_);
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const IslandBody& body = *bodies_[b];
    if (body.hasPreconditioner()) {
      body_in_[b] = r.segment(body_offsets_[b], body.dofs());
      body.applyPreconditioner(body_in_[b], body_out_[b]);
      out.segment(body_offsets_[b], body.dofs()) = body_out_[b];
      continue;
    }
    for (int k = block_starts_[b]; k < block_starts_[b + 1]; ++k) {
      const auto j = static_cast<size_t>(k);
      const auto n = inverse[j].rows();
      const int o = block_offsets_[j];
      if (n == 3) {
        blockProduct<3, 3>(inverse[j], r.data() + o, out.data() + o);
      } else if (n == 6) {
        blockProduct<6, 6>(inverse[j], r.data() + o, out.data() + o);
      } else {
        out.segment(o, n) = inverse[j] * r.segment(o, n);
      }
    }
  }
}

}  // namespace torsion::sap
