#pragma once
// Self-contact of one FEM body: its surface nodes against its own surface triangles (and its
// surface edges across each other), with Coulomb friction, inside the body's implicit step
// (docs/contact.md, "Self-contact"). Touched only by the simulation thread.
//
// Per step (the island's stages, bullet/island_step.h):
//   detect (before the solve)  the surface triangle tree (surface_tree.h) is refitted to the
//                              triangles swept over the predicted motion x + s (dt + tau_d) v,
//                              s in [0, 1] (the rows' reach, tau_d their dissipation time);
//                              every surface node queries it with its own swept box. A pair
//                              (node, triangle) is a candidate unless the triangle is in the
//                              node's one-ring (has the node as a corner), when the node lies in
//                              front of the triangle or at most max_depth behind it, and when its
//                              projection falls inside the triangle at the moment of the
//                              predicted motion where it crosses the triangle's plane (or now, if
//                              it is within the margin): a continuous test on the predicted path.
//   the solve                  the candidates are rows of the body's contact island
//                              (surface_contact_rows.h), solved with everything else it touches.
//                              After each solve the island asks for the true end gaps of the
//                              solved motion (correctGaps) and for a search along that motion
//                              (searchAlong): new candidates become new rows.
//   after the solve            takeSolution(): the rows' impulses as multipliers (the next step's
//                              lagged friction bounds) and the statistics.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "torsion/contact/surface_candidates.h"
#include "torsion/contact/surface_contact_set.h"
#include "torsion/contact/surface_pair_cache.h"
#include "torsion/fem/fem_model.h"
#include "torsion/result.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/parallel.h"

namespace torsion {

struct SelfContactSettings {
  double friction = 0.3;  ///< Coulomb coefficient between two parts of the body's surface
  /// m: the end-of-step gap every contact is driven to within (no penetration beyond it).
  /// 0: 1e-3 times the mean surface edge of the rest mesh.
  double gap_tolerance = 0;
  /// The contact thickness in units of the gap tolerance: every contact aims its end gap at
  /// thickness_factor x gap_tolerance instead of zero, so that a converged contact (its end gap
  /// within the tolerance of the target) leaves its surfaces apart, never touching
  /// (docs/contact.md, "Contact thickness"). 0: aim at zero gap, as before.
  double thickness_factor = 2;
  /// Candidates: nodes within this fraction of the mean surface edge of a triangle at the start
  /// of the step (resting contacts), besides those whose predicted path crosses it.
  double margin = 0.25;
  /// A node this fraction of the triangle's shortest edge behind it is on the far side of the
  /// body, not through the surface: no candidate (see docs/contact.md for why 0.25).
  double max_depth = 0.25;
  /// The candidate search keeps its pairs across steps while every surface node stays within
  /// this fraction of the mean surface edge of where it was when they were found
  /// (surface_pair_cache.h): the same candidates as a fresh search, most steps without a tree
  /// walk. 0: a fresh search every step.
  double search_skin = 0.25;

  Status validate() const;
};

struct SelfContactStats {
  int candidates = 0;  ///< (node, triangle) pairs this step
  int active = 0;      ///< pushing at the end of the step
  int sticking = 0;    ///< of which sticking
  int iterations = 0;  ///< Newton iterations of the island's solves this step
  int searches = 0;    ///< tree searches this step: 1, plus the re-searches along the solved motion
  int search_builds = 0;      ///< of which walked the tree (the others reused the kept pairs)
  double search_seconds = 0;  ///< s, wall time of those searches (refit, queries, candidates)
  bool converged = true;
  double normal_impulse = 0;       ///< N s, sum over active contacts
  double max_penetration = 0;      ///< m, deepest candidate node behind its triangle at the start
  double max_end_penetration = 0;  ///< m, deepest linearised end-of-step gap after the solve
};

class SelfContactSolver {
 public:
  /// Searches serially.
  SelfContactSolver(std::shared_ptr<const FemModel> model, const SelfContactSettings& settings);
  /// Searches on `parallel`'s threads (it must outlive the solver); the candidates, and so every
  /// result, are the same for any thread count.
  SelfContactSolver(std::shared_ptr<const FemModel> model, const SelfContactSettings& settings,
                    const Parallel& parallel);

  const SelfContactSettings& settings() const { return settings_; }
  /// The gap tolerance in use (m): settings().gap_tolerance or its default from the mesh.
  double gapTolerance() const { return gap_tolerance_; }
  /// m, the separation every contact aims at (thickness_factor x the gap tolerance).
  double thickness() const { return settings_.thickness_factor * gap_tolerance_; }

  /// Before the solve: candidates from the state at the start of the step and its predicted
  /// motion. Returns whether there are any.
  bool detect(const FemState& state, const NodeConstraints& constraints, double dt);
  /// After a solve with velocities v (3n): looks again along the solved motion x + s dt v, which
  /// can differ from the predicted one the candidates were found along (a kink snapping through,
  /// a loop closing), unless every node ends within half the margin of the end last searched
  /// (then any pair the solved path meets was found along that one). At most three searches
  /// per step. Returns how many candidates it added (at the end of set().contacts()).
  int searchAlong(const Eigen::VectorXd& v);
  /// After a solve with velocities v: moves the linearised gaps onto the true end-of-step
  /// geometry of the motion x + dt v: each contact whose true end gap (node against the end
  /// triangle's plane; edge against edge along the end edges' common normal, where their closest
  /// points lie inside both) is below its target by more than the tolerance, and below its
  /// linearised one, takes the difference into its gap (a secant step of the gap function).
  /// Returns how many moved.
  int correctGaps(const Eigen::VectorXd& v);
  /// The step's candidates (rows of the island), their multipliers and states.
  SurfaceContactSet& set() { return set_; }
  /// After the island's last solve (takeSurfaceContactImpulses done): the statistics, with its
  /// Newton iterations and whether it converged.
  void finishStep(int iterations, bool converged);

  const SelfContactStats& stats() const { return stats_; }
  const std::vector<SurfaceContact>& contacts() const { return set_.contacts(); }
  /// Its multipliers, all the solver carries from one step to the next (the pair cache is
  /// rebuilt when the motion leaves its skin): checkpoints save and restore them
  /// (SurfaceContactSet::save, FemBody::checkpoint).
  const SurfaceContactSet& set() const { return set_; }
  /// Live material edit: the same mesh, new masses.
  void replaceModel(std::shared_ptr<const FemModel> model) { model_ = std::move(model); }

 private:
  SelfContactSolver(std::shared_ptr<const FemModel> model, const SelfContactSettings& settings,
                    const Parallel* parallel);
  // Adds the (node, triangle) pairs found along the motion from x to end that this step does not
  // have yet, then the edge pairs; returns how many. The tree queries run in fixed blocks of
  // nodes (edges) on the threads, and the blocks' finds are added in block order.
  int addCandidates(const Eigen::VectorXd& x, const Eigen::VectorXd& end);
  // The contact of node p with triangle t along the motion, if they are a candidate (reads only).
  std::optional<SurfaceContact> nodeCandidate(int p, int t, const Eigen::VectorXd& x,
                                              const Eigen::VectorXd& end) const;
  // Edge-against-edge pairs (i, j > i) along the same motion: crossing edges that no node meets
  // (reads only; appended to out in ascending j).
  void edgeCandidates(int i, const Eigen::VectorXd& x, const Eigen::VectorXd& end,
                      std::array<std::vector<int>, 2>& scratch,
                      std::vector<SurfaceContact>& out) const;
  // Margin, depth and crease rule of the shared candidate tests (surface_candidates.h).
  CandidateRules rules() const;

  std::shared_ptr<const FemModel> model_;
  SelfContactSettings settings_;
  double mean_edge_ = 0;
  double gap_tolerance_ = 0;
  std::unique_ptr<Parallel> own_parallel_;  // serial, when no Parallel was given
  const Parallel* parallel_ = nullptr;
  std::vector<std::vector<int>> node_triangles_;  // surface triangles of each node
  std::vector<std::vector<int>> node_contacts_;   // this step's contacts of each node
  std::vector<int> touched_nodes_;                // nodes with an entry in node_contacts_
  SurfaceEdges surface_edges_;                    // surface edges and each triangle's three
  // The broad phase: the surface tree, and the pairs it found, kept across steps.
  SurfacePairCache pairs_;
  std::vector<Eigen::Vector3d> edge_lo_, edge_hi_;  // each edge's box over the searched motion
  std::vector<std::vector<SurfaceContact>> block_finds_;  // per block of nodes (edges), in order
  std::set<std::uint64_t> edge_pairs_;                    // this step's edge pairs (i << 32 | j)
  const Eigen::VectorXd* start_ = nullptr;  // positions at the step's start (the state's)
  const NodeConstraints* constraints_ = nullptr;
  SurfaceContactSet set_;
  SelfContactStats stats_;
  double dt_ = 0;
  Eigen::VectorXd end_;   // the end of the motion last searched along
  int redetections_ = 0;  // searches along the solved motion this step
};

}  // namespace torsion
