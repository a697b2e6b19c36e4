#pragma once
// One convex problem per contact island: SAP, the Semi-Analytic Primal formulation of
// A. M. Castro, F. N. Permenter, X. Han, "An Unconstrained Convex Formulation of Compliant
// Contact", IEEE Transactions on Robotics, 2023 (arXiv:2110.10107, 2022); Drake's SAP
// solver. docs/contact-sap.md explains the model; this header gives the formulas.
//
// Unknowns: v, every velocity dof of the island's bodies (island_body.h), stacked body by body.
// The velocities after the step minimise the strictly convex, C1 cost
//
//     ell(v) = 1/2 v^T A v - b^T v + sum_i ell_i(v_c,i),   v_c,i = J_i v   (contact_row.h)
//
// A = blockdiag(A_body) SPD, b the bodies' momenta with external impulses. Without contact the
// minimiser is A v = b, the bodies' own implicit step.
//
// Contact i, regularised by its physical compliance (stiffness k, dissipation time scale tau_d,
// gap phi0 at the step's start, step dt) and the Delassus estimate w_i (the paper's
// regularisation):
//
//     R_n = max(beta^2 / (4 pi^2) w_i, 1 / (dt (dt + tau_d) k))
//     R_t = sigma w_i
//     v_hat = (0, 0, -phi0 / (dt + tau_d))
//     w_i = ||W_ii||_F / 3,  W_ii = sum over the row's terms of B D^{-1} B^T
//
// The cap on R_n (near-rigid regime): the contact's period is never shorter than beta dt, which
// the step can resolve. R_t regularises friction: a stuck contact slips at R_t |gamma_t|. D is
// the block of A a term acts on, inverted on its free dofs: exact for a rigid body, for a FEM node
// the block-Jacobi estimate of its compliance. beta = 1 and sigma = 1e-3 (SapParameters).
//
// The impulse follows the lagged model (Castro, Han, Masterjohn, "A Theory of Irrotational
// Contact Fields", 2023; Drake's kLagged): the normal impulse from the compliant normal law alone,
// friction the regularised projection of the slip onto the disk of radius r = mu gamma_n^lag,
// gamma_n^lag the contact's normal impulse of the previous step (ContactRow):
//
//     gamma_n = max(0, y_n),         y_n = (v_hat - v_n) / R_n
//     gamma_t = P_r(y_t),            y_t = -v_t / R_t,  P_r the projection onto |x| <= r
//
//     stick   |y_t| <= r:  gamma_t = y_t
//     slide   otherwise:   gamma_t = r y_t / |y_t|   (|gamma_t| = r exactly, against the slip)
//
// The two parts are separable: ell_i = ell_n(v_n) + ell_t(v_t),
//
//     ell_n = 1/2 R_n gamma_n^2
//     ell_t = 1/2 R_t |gamma_t|^2          (stick)
//           = r |v_t| - 1/2 R_t r^2        (slide: Huber's function of the slip)
//
// each convex and C1 with gradient -gamma in v_c, so
//
//     gradient  g = A v - b - J^T gamma
//     Hessian   H = A + J^T G J,  G_i = -d gamma_i / d v_c,i, diagonal in (t, n), PSD:
//               G_nn = 1 / R_n if y_n > 0, else 0;
//               G_tt = I / R_t (stick), r / (|y_t| R_t) (I - t t^T) (slide), t = y_t / |y_t|.
//
// At the minimiser the normal impulse is the compliant force of the contact's spring-damper
// (within R_n), never dilated by the slip: a sliding contact rides at its rest height. Friction
// is Coulomb's with the previous step's normal impulse: stuck inside the disk, sliding on its
// circle against the slip (maximal dissipation), relaxed by R_t. The state reported is the
// friction's, stick or slide; separated where the row exerts nothing and has no curvature
// (gamma_n = 0 and r = 0: gamma = 0, G = 0). A row with r > 0 exerts its friction even in a step
// where its normal impulse falls to zero (the lag: at most mu gamma_n^lag, for one step).
//
// An anchor row (RowKind::kAnchor) is the same spring-damper in all three directions and both
// signs: gamma = (v_hat - v_c) / R_n with v_hat = (0, 0, -phi0 / (dt + tau_d)), G = I / R_n,
// ell = 1/2 R_n |gamma|^2, state stick. Convex and C1 as the contacts are.
//
// A joint row (RowKind::kJoint, one row of a Bullet joint) acts along n alone. Its target is
// Bullet's (v_hat = the row's target velocity: the joint's error times erp / dt, or a motor's
// speed), its compliance the near-rigid cap or Bullet's constraint force mixing,
// R_n = max(beta_j^2 / (4 pi^2), cfm) w with w = W_nn and beta_j = 0.1, and its impulse is clamped
// to the row's bounds [lo, hi] (a limit: one of them 0; a motor: its largest impulse):
//
//     y = (v_hat - v_n) / R_n,   gamma_n = clamp(y, lo, hi),   gamma_t = 0
//     G_nn = 1 / R_n inside (lo, hi), else 0
//     ell = 1/2 R_n y^2 inside, b R_n y - 1/2 R_n b^2 at a bound b (linear in v_n there)
//
// convex and C1 (the two pieces meet with equal value and slope at y = b). A contact's normal law
// is the case lo = 0, hi = inf. The state reported: stick inside the bounds, slide at one.
//
// Prescribed dofs (island_body.h) are held at their values: the unknowns are the free dofs, the
// gradient and every Newton direction filtered by S.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "torsion/contact/solve/contact_row.h"
#include "torsion/contact/solve/island_body.h"
#include "torsion/result.h"

namespace torsion::sap {

/// The paper's regularisation constants.
struct SapParameters {
  /// R_t = sigma w: the stiction slip relative to the velocity a row's impulse gives (1e-3, the
  /// paper's value: a thousandth of the slip-free response).
  double sigma = 1e-3;
  /// R_n >= beta^2 / (4 pi^2) w: a contact stiffer than that acts as one whose period is
  /// beta dt (near-rigid; beta = 1, the paper's value).
  double beta = 1.0;
  /// beta for joint rows: 0.1, Drake's value for its holonomic constraints
  /// (SapHolonomicConstraint).
  double joint_beta = 0.1;
};

enum class ContactState : std::uint8_t { kStick, kSlide, kSeparated };
const char* toString(ContactState state);

/// One row's regularised model, fixed for the solve.
struct RowModel {
  double mu = 0;
  double radius = 0;  ///< r = mu gamma_n^lag, N s: the friction disk's radius
  double rt = 0;      ///< R_t, m/(N s)
  double rn = 0;      ///< R_n, m/(N s)
  double v_hat = 0;   ///< v_hat_n, m/s
  double w = 0;       ///< the Delassus estimate w_i, m/(N s)
  RowKind kind = RowKind::kContact;
  double lower = 0;  ///< a joint row's impulse bounds, N s
  double upper = 0;
};

/// The projection at one contact velocity.
struct RowResponse {
  Eigen::Vector3d gamma = Eigen::Vector3d::Zero();  ///< N s, contact frame (t1, t2, n)
  Eigen::Matrix3d g = Eigen::Matrix3d::Zero();      ///< G = -d gamma / d v_c, N s^2/m
  ContactState state = ContactState::kSeparated;
  double cost = 0;  ///< ell_i = 1/2 gamma^T R gamma, J
};

/// gamma(v_c) with its G and cost (the lagged model above).
RowResponse projectImpulse(const RowModel& model, const Eigen::Vector3d& contact_velocity);

/// For a sliding contact row, the curvature its cost lacks along the slip: adds
/// r / (y_r R_t) t t^T to the tangential block of `g` (a no-op for any other row). A sliding row's
/// friction cost r |v_t| - R_t r^2 / 2 is linear along the slip direction t, so its exact G has no
/// curvature there; r / |v_t| = r / (y_r R_t) is the curvature of the quadratic that touches that
/// cost at v_t and lies above it everywhere (the majoriser of iteratively reweighted least
/// squares). G stays symmetric positive semidefinite. The Newton direction uses it where the exact
/// one failed (sap_solver.h); the cost and the line search never do.
void addSlipCurvature(const RowModel& model, const Eigen::Vector3d& contact_velocity,
                      Eigen::Matrix3d& g);

/// Everything the solver needs at one v.
struct SapEvaluation {
  Eigen::VectorXd v;
  Eigen::VectorXd av;               ///< A v
  Eigen::VectorXd contact_impulse;  ///< J^T gamma
  Eigen::VectorXd gradient;         ///< S (A v - b - J^T gamma)
  std::vector<Eigen::Vector3d> contact_velocity;
  std::vector<RowResponse> rows;
  double cost = 0;
};

class SapProblem {
 public:
  /// Fails on a malformed row (a term outside its body or not on one whole block, mu < 0, k <= 0,
  /// tau_d < 0, a negative or non-finite lagged normal impulse) or dt <= 0. The bodies are not
  /// owned and must outlive the problem; their b, diagonal blocks and free-dof projectors are read
  /// here; their products, filters and prescribed values at every solve.
  static Result<SapProblem> create(std::vector<const IslandBody*> bodies,
                                   std::vector<ContactRow> rows, double dt,
                                   const SapParameters& parameters = {});
  /// An empty problem (no bodies, no rows), to reset() later.
  SapProblem() = default;
  /// Empties the problem (no bodies, no rows), its storage kept.
  void clear();
  /// Makes this the problem create() makes from the same arguments, in the storage of the one it
  /// held: a problem kept from step to step (IslandWorkspace) allocates nothing once its bodies'
  /// blocks fit (on the 2215-node plectoneme rod, the fresh blocks' first touch was 5 % of a
  /// contact step). On failure it is left empty.
  Status reset(std::vector<const IslandBody*> bodies, std::vector<ContactRow> rows, double dt,
               const SapParameters& parameters = {});

  int dofs() const { return dofs_; }
  int rowCount() const { return static_cast<int>(rows_.size()); }
  const ContactRow& row(int i) const { return rows_[static_cast<size_t>(i)]; }
  const RowModel& model(int i) const { return models_[static_cast<size_t>(i)]; }
  /// Sets row i's lagged normal impulse (N s, finite, >= 0) and with it the radius of its
  /// friction disk, r = mu gamma_n^lag: the rest of the row's model does not depend on it, so the
  /// problem is the one create() makes from the changed row (a re-solve with matched friction
  /// bounds, rigid_contact_convex.cpp). Returns false, changing nothing, on an invalid impulse.
  bool setLaggedNormalImpulse(int i, double impulse);
  const IslandBody& body(int b) const { return *bodies_[static_cast<size_t>(b)]; }
  int bodyCount() const { return static_cast<int>(bodies_.size()); }
  /// Sets row i's gap phi0 (m, finite; a contact or anchor row) and with it its v_hat, the rest of
  /// its model unchanged: a re-solve on a gap measured again (a FEM pair's true end surface,
  /// BodyPairContact::correctGaps). Returns false, changing nothing, on a joint row or a gap that
  /// is not finite.
  bool setGap(int i, double gap);
  /// The first island dof of body `body`.
  int bodyOffset(int body) const { return body_offsets_[static_cast<size_t>(body)]; }
  const Eigen::VectorXd& momentum() const { return momentum_; }
  /// diag(A)^{-1/2}, the scaling of the optimality criterion (sap_solver.h).
  const Eigen::VectorXd& inverseSqrtDiagonal() const { return inverse_sqrt_diagonal_; }

  void multiplyA(const Eigen::VectorXd& x, Eigen::VectorXd& out) const;
  /// v_c,i = J_i v + the row's velocity offset.
  Eigen::Vector3d rowVelocity(int i, const Eigen::VectorXd& v) const;
  /// J_i x (a direction: no offset).
  Eigen::Vector3d multiplyRow(int i, const Eigen::VectorXd& x) const;
  /// out += J_i^T f.
  void addRowTranspose(int i, const Eigen::Vector3d& f, Eigen::VectorXd& out) const;
  void filter(Eigen::VectorXd& x) const;
  void impose(Eigen::VectorXd& v) const;

  /// Fills `e` at v (v already holds the prescribed values).
  void evaluate(const Eigen::VectorXd& v, SapEvaluation& e) const;
  /// The same with A v known (`av`, moved into e.av): the solver carries it along its steps.
  void evaluate(const Eigen::VectorXd& v, Eigen::VectorXd&& av, SapEvaluation& e) const;
  /// out = S H x at the evaluation's G blocks, x = S x; ax = A x (unfiltered), the part of the
  /// product the solver sums into A dv.
  void multiplyHessian(const SapEvaluation& e, const Eigen::VectorXd& x, Eigen::VectorXd& ax,
                       Eigen::VectorXd& out) const;
  /// P0, the capacitance correction's base (sap_solver.h): a body with its own preconditioner
  /// (IslandBody::hasPreconditioner) applies it, P_b ~ A_b^-1; every other body's block k is
  /// block-Jacobi's, S_k (S_k A_kk S_k + I - S_k)^{-1} S_k. `inverse`: those blocks.
  void preconditionerBlocks(std::vector<DiagonalBlock>& inverse) const;
  /// out = P0 r.
  void applyPreconditioner(const std::vector<DiagonalBlock>& inverse, const Eigen::VectorXd& r,
                           Eigen::VectorXd& out) const;
  /// A's diagonal blocks, island-wide (body after body, node or twist after the next): their
  /// count, first island dof, the block itself, S on it, and S (S A_jj S + I - S)^-1 S.
  int blockCount() const { return static_cast<int>(blocks_.size()); }
  int blockOffset(int j) const { return block_offsets_[static_cast<size_t>(j)]; }
  const DiagonalBlock& blockOfA(int j) const { return blocks_[static_cast<size_t>(j)]; }
  const DiagonalBlock& blockProjector(int j) const { return projectors_[static_cast<size_t>(j)]; }
  const DiagonalBlock& freeInverse(int j) const { return free_inverses_[static_cast<size_t>(j)]; }
  /// The island block a term acts on.
  int termBlock(const ContactTerm& term) const;
  /// Whether a body brings its own preconditioner (then sap_solver.h may use the capacitance
  /// correction).
  bool hasBodyPreconditioner() const;

 private:
  // The rest of evaluate, with e.av already A v.
  void evaluateWithAv(const Eigen::VectorXd& v, SapEvaluation& e) const;
  Status validate(const ContactRow& row) const;
  Status validateTerms(const ContactRow& row) const;
  void collectBlocks();
  RowModel makeModel(const ContactRow& row, double dt, const SapParameters& parameters) const;
  // The island dof of a term's first column.
  int termOffset(const ContactTerm& term) const { return bodyOffset(term.body) + term.first_dof; }

  std::vector<const IslandBody*> bodies_;
  std::vector<ContactRow> rows_;
  std::vector<RowModel> models_;
  std::vector<int> body_offsets_;          // dofs
  std::vector<int> block_starts_;          // first global block of each body, then the block count
  std::vector<int> block_offsets_;         // first island dof of each block
  std::vector<DiagonalBlock> blocks_;      // A's diagonal blocks
  std::vector<DiagonalBlock> projectors_;  // S per block
  // S (S A_kk S + I - S)^-1 S per block, made once: block-Jacobi's block wherever no row acts.
  std::vector<DiagonalBlock> free_inverses_;
  int dofs_ = 0;
  double dt_ = 0;
  Eigen::VectorXd momentum_;
  Eigen::VectorXd inverse_sqrt_diagonal_;
  // Per-body scratch of multiplyA (one solve thread per problem).
  mutable std::vector<Eigen::VectorXd> body_in_, body_out_;
};

}  // namespace torsion::sap
