#pragma once
// Node-against-triangle (and edge-against-edge) contacts between FEM surfaces (one body against
// itself: self_contact.h), solved inside the implicit step's linear solves by an augmented
// Lagrangian (docs/contact.md, "Self-contact"). Touched only by the simulation thread.
//
// A contact c joins a surface node p and a surface triangle (a, b, c) it must not pass through.
// With the triangle point's barycentric weights w, the relative velocity is
//   u = v_p - (w_a v_a + w_b v_b + w_c v_c) = sum_k beta_k v_k,   beta = (1, -w_a, -w_b, -w_c),
// and the linearised gap at the end of the step is gap + dt n.u >= d (n: the triangle's outward
// normal at the step's start; d the contact's target_gap, its thickness: the solve aims at a small
// separation so that surfaces it holds never touch, docs/contact.md, "Contact thickness"). The
// impulse lambda (N s) acts on p and -w_j lambda on the triangle's corners, so the pair exchanges
// momentum exactly (sum beta_k = 0) and, the lever being the same point, angular momentum up to the
// linearisation.
//
// Augmented Lagrangian (Alart & Curnier 1991; Uzawa's update) for the normal impulse, with
// Coulomb's friction implicit in the tangential direction. Each linear solve takes the impulse as
//   sticking: lambda = Lambda - rho h,                         h = u + n (gap - d) / dt,
//   sliding:  lambda = n (n.Lambda - rho n.h) - k_t (I - n n^T) u,
// which adds rho beta_k beta_l I (sticking) or beta_k beta_l (rho n n^T + k_t (I - n n^T))
// (sliding) to the system (this class is the AddedOperatorTerm) and beta_k (Lambda - rho n (gap -
// d) / dt) to its right-hand side (only Lambda's normal part when sliding). After each solve
// update() projects on Coulomb's cone: lambda_n = max(0, n.Lambda - rho n.h); a sticking contact
// keeps Lambda - rho h while its tangential part stays within mu lambda_n; a sliding one gets k_t =
// mu lambda_n / |u_t| (at most rho: below the slip speed mu lambda_n / rho it sticks again), so its
// friction impulse -k_t u_t is Coulomb's, opposes the slip of the same solve and can never reverse
// it (a fixed point of lagged stiffnesses: Kacanov's iteration, not an explicit force). rho is
// `penalty_factor` times the contact's effective mass from the system's 3x3 diagonal blocks.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "torsion/solve/added_operator_term.h"

namespace torsion {

struct SurfaceContact {
  enum class State : std::uint8_t { kInactive, kStick, kSlide };
  std::array<int, 4> nodes{};    ///< p, then the triangle's corners (indices of the solve)
  std::array<double, 4> beta{};  ///< 1, -w_a, -w_b, -w_c
  int triangle = -1;       ///< the triangle's index, or the second edge's for an edge pair (key)
  int edge = -1;           ///< edge-against-edge: the first edge's index (key); -1: node-triangle
  Eigen::Vector3d normal;  ///< unit, the triangle's outward normal at the step's start
  double gap = 0;          ///< m, signed distance of p along normal, start of the step
  /// m, the separation the solve drives the end gap to (the contact thickness, >= 0): the
  /// constraint is gap + dt n.u >= target_gap. The impulses' weights are unchanged (sum beta_k =
  /// 0), so momentum is exchanged exactly whatever it is.
  double target_gap = 0;
  double friction = 0;                                   ///< Coulomb coefficient mu
  double penalty = 0;                                    ///< rho, kg
  Eigen::Vector3d multiplier = Eigen::Vector3d::Zero();  ///< Lambda, N s on p
  State state = State::kInactive;
  bool determined = false;  ///< all four nodes fully prescribed: sits the solves out
  int releases = 0;         ///< releases this step (anti-cycling: one)
  int switches = 0;         ///< stick/slide switches this step (anti-cycling: then it stays)
  /// kg, sliding: k_t, the friction impulse being -k_t u_t (the tangential relative velocity);
  /// at most the penalty. Negative: the penalty (a warm-started contact's first solve).
  double tangential_stiffness = 0;
  /// m, the linearised end-of-step gap after the last solve, less target_gap (< 0: inside the
  /// contact's thickness).
  double end_gap = 0;
};

class SurfaceContactSet final : public AddedOperatorTerm {
 public:
  /// Forgets the last step's candidates; their multipliers stay as warm starts (keyed by node and
  /// triangle) for add().
  void beginStep();
  /// A candidate for this step (state kInactive unless a warm start makes it active).
  void add(SurfaceContact contact);
  /// Whether (node, triangle) was active at the end of the last step (has a warm start).
  bool wasActive(int node, int triangle) const {
    return warmStartOf(key(node, triangle)) != nullptr;
  }
  /// The multiplier a contact with these keys ended the last step with, or nullptr.
  const Eigen::Vector3d* warmStartOf(const SurfaceContact& c) const { return warmStartOf(key(c)); }
  std::vector<SurfaceContact>& contacts() { return contacts_; }
  const std::vector<SurfaceContact>& contacts() const { return contacts_; }
  bool empty() const { return contacts_.empty(); }

  /// A sliding contact that keeps sliding takes this fraction of the k_t its slip asks for and
  /// keeps the rest of its last one (1, the default: all of it). Below 1 damps the two-cycle
  /// Kacanov's iteration can fall into when k_t and the slip's speed trade places from one
  /// update to the next (measured between FEM bodies: body_pair_contact.h uses 0.5).
  void setFrictionRelaxation(double fraction) { friction_relaxation_ = fraction; }
  /// rho of every contact from the system's diagonal blocks (without this term).
  void setPenalties(const std::vector<Eigen::Matrix3d>& diagonal_blocks, double penalty_factor);
  /// The contact's block of the operator: rho I sticking, rho n n^T + k_t (I - n n^T) sliding
  /// (its impulse on the relative velocity u is -block u beyond the right-hand side's).
  static Eigen::Matrix3d operatorBlock(const SurfaceContact& c);
  /// N s: what the contact puts on the right-hand side (times beta_k on its nodes): Lambda
  /// (sliding: its normal part; the friction is in the operator) less rho n (gap - target_gap) /
  /// dt.
  static Eigen::Vector3d rightHandSideImpulse(const SurfaceContact& c, double dt);
  /// Marks contacts whose nodes the solve cannot move (is_fixed(node) for all four).
  template <typename IsFixed>
  void markDetermined(IsFixed is_fixed) {
    for (SurfaceContact& c : contacts_) {
      c.determined = true;
      for (int node : c.nodes)
        c.determined = c.determined && is_fixed(node);
    }
  }
  /// b += sum over active contacts of beta_k (Lambda - rho n (gap - target_gap) / dt).
  void addRightHandSide(double dt, Eigen::VectorXd& b) const;
  /// Uzawa's projection after a solve with velocities v (3n). Activates contacts whose end gap is
  /// below target_gap - activation_tolerance. Gaps below are judged against target_gap. Returns
  /// whether the set has converged: no contact changed state, every end gap within gap_tolerance
  /// (no penetration beyond it, no active contact pushing across a gap beyond it), no sticking
  /// contact slipping more than gap_tolerance and every sliding contact's friction impulse within 2
  /// % of mu lambda_n of the last solve's.
  bool update(const Eigen::VectorXd& v, double dt, double activation_tolerance,
              double gap_tolerance);
  /// Whether update() judges convergence by what the last solve's motion is off by, rather than
  /// by the states settling: the solve's impulse minus the one Uzawa's projection gives (a pull
  /// that releases a contact, friction beyond Coulomb's cone that makes it slide, a sliding
  /// friction impulse that changes), over the contact's effective mass (its penalty over
  /// penalty_factor), times dt, must be at most gap_tolerance: the same geometric accuracy as
  /// the end gaps and a sticking contact's slip. A state change alone (an activation within the
  /// tolerance, a switch with a negligible impulse) then no longer keeps the loop going, nor
  /// does a sliding impulse still moving by more than 2 % of mu lambda_n with no effect on the
  /// motion. Off by default (the changes of state count).
  void setConvergedWithinTolerance(bool on) { within_tolerance_ = on; }
  /// m, the deepest linearised end-of-step penetration of any candidate (>= 0): below zero gap,
  /// not below its target_gap.
  double maxEndPenetration() const;
  /// m, the largest gap error after the last update: any candidate's end gap below its target,
  /// or an active contact's end gap away from its target.
  double maxGapError() const;

  // AddedOperatorTerm: beta_k beta_l (rho I or rho n n^T + k_t (I - n n^T)) of the active contacts.
  void addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const override;
  void addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const override;
  /// While suspended the term adds nothing (the penalties are taken from A alone).
  void setSuspended(bool suspended) { suspended_ = suspended; }

  /// Warm starts the next step starts from: (key, Lambda) of the active contacts, sorted by key.
  using WarmStarts = std::vector<std::pair<std::uint64_t, Eigen::Vector3d>>;
  WarmStarts warmStarts() const;
  /// Back to warm starts taken by warmStarts() (checkpoints): the next beginStep() uses them.
  void setWarmStarts(WarmStarts warm) {
    contacts_.clear();
    warm_ = std::move(warm);
    restored_ = true;
  }

 private:
  static std::uint64_t key(const SurfaceContact& c) {
    return c.edge >= 0 ? key(-1 - c.edge, c.triangle) : key(c.nodes[0], c.triangle);
  }
  static std::uint64_t key(int node, int triangle) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(node)) << 32) |
           static_cast<std::uint32_t>(triangle);
  }
  const Eigen::Vector3d* warmStartOf(std::uint64_t k) const;
  bool participates(const SurfaceContact& c) const {
    return !suspended_ && !c.determined && c.state != SurfaceContact::State::kInactive;
  }
  Eigen::Vector3d relativeVelocity(const SurfaceContact& c, const Eigen::VectorXd& v) const;
  // Whether `impulse` (N s) on c moves it by more than gap_tolerance over the step.
  bool beyondTolerance(const SurfaceContact& c, double impulse, double dt,
                       double gap_tolerance) const;

  std::vector<SurfaceContact> contacts_;
  WarmStarts warm_;  // the last step's, looked up by add()
  bool suspended_ = false;
  double friction_relaxation_ = 1;
  bool within_tolerance_ = false;
  double penalty_factor_ = 1;  // the last setPenalties' (rho over the effective mass)
  bool restored_ = false;      // warm_ was set by setWarmStarts: beginStep keeps it
};

}  // namespace torsion
