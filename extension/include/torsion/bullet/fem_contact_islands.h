#pragma once
// Contact between FEM bodies in a Bullet world (docs/contact.md, "Contact between FEM bodies"):
// which bodies touch, grouped into islands, and each island stepped with its bodies' velocities
// solved together (contact/island_contact.h). Owned by FemSoftBodySolver; simulation thread only.
//
// Per substep:
//   notePair   Bullet's broadphase hands over the FEM pairs whose boxes (over the predicted
//              motion) overlap (FemSoftBodySolver::processCollision)
//   plan       each such pair looks for contact candidates (BodyPairContact::detect); pairs with
//              candidates join their bodies into islands (connected components), in body order
//   advance    a lone body steps as always (FemBody::advance); an island's bodies step in stages:
//              every body prepares its step (FemBody::prepare: forces, b, its system with the pair
//              contacts' term added), the island solve runs once on all their systems, then
//              every body finishes its step with the velocities the island solve left it
//              (FemBody::finish: integration, health). A body whose prepare fails (non-finite
//              forces) leaves the island; its pairs sit the step out.
// Bodies apart cost nothing: no pair is noted, nothing is detected.

#include <cstdint>
#include <map>
#include <memory>
#include <utility>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/step_context.h"
#include "torsion/contact/body_pair_contact.h"
#include "torsion/contact/island_contact.h"
#include "torsion/contact/solve/sap_problem.h"

namespace torsion {

/// The last substep's contact between FEM bodies, summed over its islands.
struct FemContactStats {
  int touching_pairs = 0;  ///< pairs whose boxes overlap
  int islands = 0;         ///< islands of two or more bodies
  int candidates = 0;      ///< node-triangle pairs
  int active = 0;          ///< pushing at the end of the step
  int sticking = 0;        ///< of which sticking
  int iterations = 0;      ///< the most of any island: Newton iterations (convex) or Uzawa updates
  bool converged = true;   ///< every island
  double normal_impulse = 0;       ///< N s, sum over active contacts
  double max_end_penetration = 0;  ///< m, deepest linearised end gap
};

/// One touching pair's multipliers, the warm starts its next step starts from (checkpoints).
struct FemPairCheckpoint {
  const FemBody* a = nullptr;  ///< the pair's first body (the earlier in the solver's order)
  const FemBody* b = nullptr;
  SurfaceContactSet::WarmStarts warm_starts;
};

class FemContactIslands {
 public:
  explicit FemContactIslands(const BodyContactSettings& settings) : settings_(settings) {}

  const BodyContactSettings& settings() const { return settings_; }

  /// A new substep: forget the last one's broadphase pairs.
  void beginSubstep() { touching_.clear(); }
  /// Bullet's broadphase: the boxes of these two FEM bodies overlap this substep.
  void notePair(FemBody* a, FemBody* b);
  /// The body is being removed: its pairs go.
  void forget(const FemBody* body);

  /// Groups `bodies` (the solver's order) for this step: islands of touching bodies and lone
  /// bodies, each group in body order, groups in the order of their first body.
  std::vector<std::vector<FemBody*>> plan(const std::vector<FemBody*>& bodies,
                                          const StepContext& ctx);
  /// Steps one group from plan(): a lone body as always, an island as one system.
  void advance(const std::vector<FemBody*>& group, const StepContext& ctx);

  const FemContactStats& stats() const { return stats_; }
  /// Every pair's multipliers now, in key order: what the next step takes over from the last.
  std::vector<FemPairCheckpoint> checkpoint() const;
  /// Back to `pairs` (from checkpoint()): the pairs now kept are dropped, those saved come back
  /// with their multipliers, so the next step is bit for bit the one that followed the save.
  void restore(const std::vector<FemPairCheckpoint>& pairs);
  /// The pair contact of two bodies (either order), or nullptr when they are not touching.
  const BodyPairContact* pair(const FemBody* a, const FemBody* b) const;

 private:
  using Key = std::pair<const FemBody*, const FemBody*>;
  // The island's slots, its pairs (those of live_ inside the group) and each body's pair term.
  void setUpIsland(const std::vector<FemBody*>& group);
  // Body k's prepared system into its slot, with its own contact solve where it keeps one.
  void enter(size_t k, FemBody* body);
  // Whether the island is stepped as one convex problem (fem_convex_island.cpp): every body's
  // contacts use the convex solve, none has self-contact or a hyperelastic law.
  static bool convexIsland(const std::vector<FemBody*>& group);
  // Steps the island as one convex problem; returns whether any body got to its solve.
  bool advanceConvex(const std::vector<FemBody*>& group, const StepContext& ctx);
  // The pairs' gaps onto their true end surface at the island's velocities x; returns how many
  // rows of `problem` changed their gap (fem_convex_island.cpp).
  int correctPairGaps(sap::SapProblem& problem, const Eigen::VectorXd& x,
                      const std::vector<int>& island_body, const std::vector<int>& pair_first,
                      double dt);
  // The island's statistics into stats_; a warning on its bodies when `solved` did not converge.
  void addStats(const std::vector<FemBody*>& group, bool solved);

  BodyContactSettings settings_;
  std::vector<std::pair<FemBody*, FemBody*>> touching_;    // this substep's, as Bullet gave them
  std::map<Key, std::unique_ptr<BodyPairContact>> pairs_;  // keyed by (lower, higher) index
  std::vector<std::pair<Key, BodyPairContact*>> live_;     // pairs with candidates, in body order
  FemContactStats stats_;

  // The island being stepped.
  std::vector<IslandContactSolve::Body> slots_;
  std::vector<IslandContactSolve::Pair> island_pairs_;
  std::vector<PairContactTerm> terms_;
  IslandContactStats island_stats_;
  IslandContactSolve solver_;
};

}  // namespace torsion
