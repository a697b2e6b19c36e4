#pragma once
// Self-contact of one FEM body: its surface nodes against its own surface triangles, with
// Coulomb friction, inside the body's implicit step (docs/contact.md, "Self-contact"). Touched
// only by the simulation thread.
//
// Per step:
//   detect (before the solve)  the surface triangle tree (surface_tree.h) is refitted to the
//                              triangles swept over the predicted motion x + s dt v, s in [0, 1];
//                              every surface node queries it with its own swept box. A pair
//                              (node, triangle) is a candidate unless the triangle is in the
//                              node's one-ring (has the node as a corner), when the node lies in
//                              front of the triangle or at most max_depth behind it, and when its
//                              projection falls inside the triangle at the moment of the
//                              predicted motion where it crosses the triangle's plane (or now, if
//                              it is within the margin): a continuous test on the predicted path.
//   solve (the step's solve)   the candidates' augmented Lagrangian (surface_contact_set.h) is
//                              added to the body's system operator; Uzawa updates alternate with
//                              warm-started CG solves until every end-of-step gap is within
//                              gap_tolerance (or max_iterations: reported, not accepted
//                              silently). With rigid contacts in the same step, the rigid
//                              contact solve runs once on the augmented system and the
//                              multipliers are updated once (the gap then converges over steps).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
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
#include "torsion/solve/projected_cg.h"
#include "torsion/solve/solver_settings.h"
#include "torsion/solve/system_operator.h"

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
  /// rho in units of the contact's effective mass (surface_contact_set.h). Stiffer converges the
  /// normal gap in fewer updates but each CG solve takes longer and friction settles worse: on
  /// six steps of the plectoneme's contact phase 8 took half the CPU time of 20 (60: a quarter
  /// more than 20); 2 left steps unconverged (docs/contact.md).
  double penalty_factor = 8;
  /// Uzawa updates (each one warm-started CG solve) per step.
  int max_iterations = 40;
  /// The CG tolerance of the rough rounds, in units of the solver's: the Uzawa updates start on
  /// solves this much less accurate, and the step goes on with accurate ones once they settle,
  /// once three rough rounds in a row did worse, or after a quarter of max_iterations (it ends
  /// on an accurate solve, judged as before). 1: every solve accurate. On the plectoneme's
  /// contact phase 100 took 31 % less CPU than 1, and 30 only 13 % less (docs/performance.md).
  double rough_tolerance_factor = 100;
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
  int iterations = 0;  ///< Uzawa updates (CG solves) this step
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
  /// The augmented Lagrangian term to add to the body's system operator for this step.
  const AddedOperatorTerm& term() const { return set_; }
  /// The step's linear solve, on the stepper's prepared system with term() added
  /// (ImplicitStepper::prepared(); FemBody::solveContacts). `inner`, when given, is the solve that
  /// would run without self-contact (the rigid contact solve): it runs once on the augmented
  /// system. Without it, CG solves alternate with Uzawa updates until converged.
  using InnerSolve = std::function<LinearSolveReport(const SystemOperator&, const NodeConstraints&,
                                                     const Eigen::VectorXd&, const SolverSettings&,
                                                     Eigen::VectorXd&)>;
  LinearSolveReport solve(const SystemOperator& op, const NodeConstraints& constraints,
                          const Eigen::VectorXd& b, const SolverSettings& settings,
                          Eigen::VectorXd& v, const InnerSolve& inner);

  const SelfContactStats& stats() const { return stats_; }
  const std::vector<SurfaceContact>& contacts() const { return set_.contacts(); }
  /// The multipliers the next step starts from (checkpoints).
  SurfaceContactSet::WarmStarts warmStarts() const { return set_.warmStarts(); }
  void restoreWarmStarts(SurfaceContactSet::WarmStarts warm) {
    set_.setWarmStarts(std::move(warm));
  }
  /// Live material edit: the same mesh, new masses.
  void replaceModel(std::shared_ptr<const FemModel> model) { model_ = std::move(model); }

 private:
  SelfContactSolver(std::shared_ptr<const FemModel> model, const SelfContactSettings& settings,
                    const Parallel* parallel);
  // Adds the (node, triangle) pairs found along the motion from x to end that this step does not
  // have yet, then the edge pairs; returns how many. The tree queries run in fixed blocks of
  // nodes (edges) on the threads, and the blocks' finds are added in block order.
  int addCandidates(const Eigen::VectorXd& x, const Eigen::VectorXd& end);
  // Moves the linearised gaps onto the true end-of-step geometry of the solved motion x + dt v:
  // each contact whose true end gap (node against the end triangle's plane; edge against edge
  // along the end edges' common normal, where their closest points lie inside both) is below
  // its target by more than the tolerance, and below its linearised one, takes the difference
  // into its gap (a secant step of the gap function). Returns how many moved.
  int correctGaps(const Eigen::VectorXd& v);
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
  ProjectedCg cg_;
  std::vector<Eigen::Matrix3d> blocks_;
  Eigen::VectorXd end_, b_aug_, best_v_;
  std::vector<SurfaceContact> best_contacts_;
  bool penalties_ready_ = false;  // blocks_ hold this step's diagonal blocks
};

}  // namespace torsion
