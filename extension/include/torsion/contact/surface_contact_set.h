#pragma once
// Node-against-triangle (and edge-against-edge) contacts between FEM surfaces: one body against
// itself (self_contact.h) or two touching bodies (body_pair_contact.h). The set holds a step's
// candidates and their multipliers; the contact island solves them as rows
// (contact/solve/surface_contact_rows.h). Touched only by the simulation thread.
//
// A contact c joins a surface node p and a surface triangle (a, b, c) it must not pass through.
// With the triangle point's barycentric weights w, the relative velocity is
//   u = v_p - (w_a v_a + w_b v_b + w_c v_c) = sum_k beta_k v_k,   beta = (1, -w_a, -w_b, -w_c),
// and the linearised gap at the end of the step is gap + dt n.u >= d (n: the triangle's outward
// normal at the step's start; d the contact's target_gap, its thickness: the solve aims at a small
// separation so that surfaces it holds never touch, docs/contact.md, "Contact thickness"). The
// impulse lambda (N s) acts on p and -w_j lambda on the triangle's corners, so the pair exchanges
// momentum exactly (sum beta_k = 0) and, the lever being the same point, angular momentum up to the
// linearisation. An edge crossing an edge is the same with beta = (1 - s, s, -(1 - t), -t).
//
// Each step starts from the last one's multipliers, keyed by node (or edge) and triangle (or
// edge): a contact that pushed at the end of the last step starts with that impulse, projected
// onto its new friction cone (the lagged friction bound of the next solve).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "torsion/checkpoint_stream.h"

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
  Eigen::Vector3d multiplier = Eigen::Vector3d::Zero();  ///< Lambda, N s on p
  State state = State::kInactive;
  bool determined = false;  ///< all four nodes fully prescribed: nothing to solve
  /// m, the linearised end-of-step gap after the last solve, less target_gap (< 0: inside the
  /// contact's thickness).
  double end_gap = 0;
};

class SurfaceContactSet {
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

  /// Marks contacts whose nodes the solve cannot move (is_fixed(node) for all four).
  template <typename IsFixed>
  void markDetermined(IsFixed is_fixed) {
    for (SurfaceContact& c : contacts_) {
      c.determined = true;
      for (int node : c.nodes)
        c.determined = c.determined && is_fixed(node);
    }
  }
  /// m, the deepest linearised end-of-step penetration of any candidate (>= 0): below zero gap,
  /// not below its target_gap.
  double maxEndPenetration() const;

  /// Warm starts the next step starts from: (key, Lambda) of the active contacts, sorted by key.
  using WarmStarts = std::vector<std::pair<std::uint64_t, Eigen::Vector3d>>;
  WarmStarts warmStarts() const;
  /// Back to warm starts taken by warmStarts(): the next beginStep() uses them.
  void setWarmStarts(WarmStarts warm) {
    contacts_.clear();
    warm_ = std::move(warm);
    restored_ = true;
  }
  /// The checkpoint's bytes of the warm starts the next beginStep() takes (checkpoint_stream.h):
  /// the multipliers of the self-contact of a body (SelfContactSolver::set) or of a touching pair
  /// (BodyPairContact::set).
  void save(CheckpointWriter& out) const;
  /// Back to bytes of save() (setWarmStarts). Errors, changing nothing: bytes cut short, keys
  /// out of order or multipliers not finite.
  Status restore(CheckpointReader& in);

 private:
  static std::uint64_t key(const SurfaceContact& c) {
    return c.edge >= 0 ? key(-1 - c.edge, c.triangle) : key(c.nodes[0], c.triangle);
  }
  static std::uint64_t key(int node, int triangle) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(node)) << 32) |
           static_cast<std::uint32_t>(triangle);
  }
  const Eigen::Vector3d* warmStartOf(std::uint64_t k) const;

  std::vector<SurfaceContact> contacts_;
  WarmStarts warm_;        // the last step's, looked up by add()
  bool restored_ = false;  // warm_ was set by setWarmStarts: beginStep keeps it
};

}  // namespace torsion
