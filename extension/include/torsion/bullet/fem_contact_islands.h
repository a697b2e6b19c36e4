#pragma once
// Contact between FEM bodies in a Bullet world (docs/contact.md, "Contact between FEM bodies"):
// which bodies touch, grouped into islands, and each island stepped as one convex problem
// (island_step.h). Owned by FemSoftBodySolver; simulation thread only.
//
// Per substep:
//   notePair   Bullet's broadphase hands over the FEM pairs whose boxes (over the predicted
//              motion) overlap (FemSoftBodySolver::processCollision)
//   plan       each such pair looks for contact candidates (BodyPairContact::detect); pairs with
//              candidates join their bodies into islands (connected components), in body order
//   advance    each group steps as one island with its pairs' candidates (stepIsland)
// Bodies apart cost nothing: no pair is noted, nothing is detected.

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/island_step.h"
#include "torsion/bullet/step_context.h"
#include "torsion/contact/body_pair_contact.h"

namespace torsion {

/// The last substep's contact between FEM bodies, summed over its islands.
struct FemContactStats {
  int touching_pairs = 0;          ///< pairs whose boxes overlap
  int islands = 0;                 ///< islands of two or more bodies
  int candidates = 0;              ///< node-triangle pairs
  int active = 0;                  ///< pushing at the end of the step
  int sticking = 0;                ///< of which sticking
  int iterations = 0;              ///< the most of any island: Newton iterations
  bool converged = true;           ///< every island
  double normal_impulse = 0;       ///< N s, sum over active contacts
  double max_end_penetration = 0;  ///< m, deepest linearised end gap
};

/// One touching pair's multipliers, the warm starts its next step starts from (checkpoints).
struct FemPairCheckpoint {
  const FemBody* a = nullptr;  ///< the pair's first body (the earlier in the solver's order)
  const FemBody* b = nullptr;
  /// Its multipliers as bytes (SurfaceContactSet::save of BodyPairContact::set): a file holds
  /// these bytes.
  std::string multipliers;
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
  /// Steps one group from plan() as one island (stepIsland) with its pairs.
  void advance(const std::vector<FemBody*>& group, const StepContext& ctx,
               IslandWorkspace& workspace);

  const FemContactStats& stats() const { return stats_; }
  /// Every pair's multipliers now, in key order: what the next step takes over from the last.
  std::vector<FemPairCheckpoint> checkpoint() const;
  /// Back to `pairs` (from checkpoint(), or read by readCheckpoint: they pass checkRestore): the
  /// pairs now kept are dropped, those saved come back with their multipliers, so the next step
  /// is bit for bit the one that followed the save.
  void restore(const std::vector<FemPairCheckpoint>& pairs);
  /// Whether the multipliers' bytes of `pairs` read, read as restore() reads them (onto scratch
  /// sets: nothing changes). Errors name the pair.
  static Status checkRestore(const std::vector<FemPairCheckpoint>& pairs);
  /// The pair contact of two bodies (either order), or nullptr when they are not touching.
  const BodyPairContact* pair(const FemBody* a, const FemBody* b) const;

 private:
  using Key = std::pair<const FemBody*, const FemBody*>;
  BodyContactSettings settings_;
  std::vector<std::pair<FemBody*, FemBody*>> touching_;    // this substep's, as Bullet gave them
  std::map<Key, std::unique_ptr<BodyPairContact>> pairs_;  // keyed by (lower, higher) index
  std::vector<std::pair<Key, BodyPairContact*>> live_;     // pairs with candidates, in body order
  FemContactStats stats_;
};

}  // namespace torsion
