#pragma once
// Contact between two FEM bodies (docs/contact.md, "Contact between FEM bodies"): the surface
// nodes of each body against the surface triangles of the other, with Coulomb friction. One
// BodyPairContact per pair of bodies whose bounding boxes overlap; it lives as long as they do,
// so its multipliers warm-start the next step. Touched only by the simulation thread.
//
// Index space: the pair's nodes are body a's nodes, then body b's (node k of b is a.nodeCount() +
// k); triangles likewise (b's are offset by a's surface triangle count). Its SurfaceContactSet
// holds the candidates in that space with the same constraint as self-contact: with the
// triangle point's barycentric weights w, beta = (1, -w_a, -w_b, -w_c), relative velocity
// u = sum_k beta_k v_k, linearised end-of-step gap g + dt n.u >= 0. Since sum_k beta_k = 0, an
// impulse lambda on the node and -w_j lambda on the triangle's corners exchanges momentum exactly.
// The contact island (bullet/island_step.h) solves them as rows.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>
#include <vector>

#include "torsion/contact/surface_candidates.h"
#include "torsion/contact/surface_contact_set.h"
#include "torsion/contact/surface_tree.h"
#include "torsion/fem/fem_model.h"
#include "torsion/result.h"

namespace torsion {

/// Contact between FEM bodies, one setting for every pair of a world (FemSoftBodySolver).
struct BodyContactSettings {
  double friction = 0.3;  ///< Coulomb coefficient between two FEM bodies' surfaces
  /// m: the end-of-step gap every contact is driven to within (no penetration beyond it).
  /// 0: 1e-3 times the smaller of the two bodies' mean surface edges (rest mesh).
  double gap_tolerance = 0;
  /// The contact thickness in units of the gap tolerance: every contact aims its end gap at
  /// thickness_factor x gap_tolerance instead of zero, so that bodies held apart by contact do
  /// not touch (docs/contact.md, "Contact thickness"). 0: aim at zero gap, as before.
  double thickness_factor = 2;
  /// Candidates: nodes within this fraction of the triangle body's mean surface edge of a
  /// triangle at the start of the step, besides those whose predicted path crosses it.
  double margin = 0.25;
  /// A node this fraction of the triangle's shortest edge behind it is deep inside the other body
  /// (on its far side), not through its surface: no candidate.
  double max_depth = 0.25;
  /// Edge-against-edge candidates besides node-against-triangle ones: two edges crossing where
  /// no node meets a face (an edge across an edge). On by default: with them the exact checker
  /// finds fewer crossings in the contact scenes (soft_stack: 360 crossing triangle pairs over
  /// 200 steps instead of 4266), and their own tests pass (docs/contact.md, "Edge against edge
  /// between bodies").
  bool edge_edge = true;

  Status validate() const;
};

class BodyPairContact {
 public:
  BodyPairContact(std::shared_ptr<const FemModel> a, std::shared_ptr<const FemModel> b,
                  const BodyContactSettings& settings);

  /// Candidates for this step from both bodies' positions at the step's start and their
  /// predicted motion x + s dt v, s in [0, 1] (the same tests as self-contact: within the margin
  /// now, or crossing on the path, projection inside the triangle then; only where the node's
  /// surface faces the triangle, its normal against the triangle's). Last step's multipliers
  /// become warm starts. Returns whether there are any.
  bool detect(const Eigen::VectorXd& xa, const Eigen::VectorXd& va, const Eigen::VectorXd& xb,
              const Eigen::VectorXd& vb, double dt);

  /// The true end of the step after a solve with the pair's velocities v (a's, then b's; m/s):
  /// a candidate whose node, moved to x + dt v, projects inside its moved triangle (same slack
  /// as detection) and lies more than `tolerance` behind the moved triangle's plane has its gap
  /// shifted by the difference between that true end gap and its linearised one
  /// (gap + dt n.u), so the next solve aims at the surface where it really ends up, not where
  /// the start-of-step plane put it (a triangle that tilts or stretches while nodes slide over
  /// it). Normals and weights stay those of detection, so the impulses stay equal and opposite
  /// with the same levers. Returns how many gaps were shifted (docs/contact.md, "Fast impacts").
  int correctGaps(const Eigen::VectorXd& v, double dt, double tolerance);

  int nodeCountA() const { return node_count_a_; }
  /// m, the gap tolerance in use (settings or its default from the two meshes).
  double gapTolerance() const { return gap_tolerance_; }
  /// m, the separation every contact aims at (thickness_factor x the gap tolerance).
  double thickness() const { return settings_.thickness_factor * gap_tolerance_; }
  const BodyContactSettings& settings() const { return settings_; }
  SurfaceContactSet& set() { return set_; }
  const SurfaceContactSet& set() const { return set_; }
  /// Live material edit of either body: same meshes, new masses (nothing here depends on them).
  void replaceModels(std::shared_ptr<const FemModel> a, std::shared_ptr<const FemModel> b);

 private:
  // Surface nodes of `nodes_model` (offset `node_offset` in the pair) against the surface
  // triangles of `tree` (corners offset by `triangle_node_offset`, indices by
  // `triangle_offset`).
  void addCandidates(const FemModel& nodes_model, int node_offset, const Eigen::VectorXd& xn,
                     const Eigen::VectorXd& en, const Eigen::VectorXd& node_normals,
                     SurfaceTree& tree, int triangle_node_offset, int triangle_offset,
                     const Eigen::VectorXd& xt, const Eigen::VectorXd& et, double margin);

  // a's surface edges against b's (b's tree refitted to b's motion): the crossings of two edges
  // that no node meets, as in self-contact; keyed (a's edge, b's edge).
  CandidateRules candidateRules(double margin) const;
  // Whether edge pair `pair` (a's edge e against b's edge f, positions x and predicted e) joins two
  // flat parts of surfaces that do not face each other (outward normals n_a . n_b above -0.25)
  // while the bodies slide along one of them (the step's relative motion within 75.5 deg of its
  // plane): a side face moving over the face it stands on, whose corner the nodes and the bodies'
  // sharp edges hold. As a new pair it is a wall: a block's side-face diagonal, rising from its
  // bottom node, met a slab edge lying in their contact plane just ahead of it and threw the
  // sliding block back (frictionless at 20 deg: 47 % of Coulomb's distance). Faces meeting
  // head-on, or approaching across both faces (two cubes thrown together), still pair.
  bool slidesAlongFlatFaces(const SurfaceContact& pair, const std::array<int, 2>& e,
                            const std::array<int, 2>& f, const Eigen::VectorXd& xa,
                            const Eigen::VectorXd& ea, const Eigen::VectorXd& xb,
                            const Eigen::VectorXd& eb) const;
  void addEdgeCandidates(const Eigen::VectorXd& xa, const Eigen::VectorXd& ea,
                         const Eigen::VectorXd& xb, const Eigen::VectorXd& eb, double margin);

  std::shared_ptr<const FemModel> a_, b_;
  BodyContactSettings settings_;
  int node_count_a_ = 0;
  int triangle_count_a_ = 0;
  double mean_edge_a_ = 0, mean_edge_b_ = 0;
  double gap_tolerance_ = 0;
  SurfaceTree tree_a_, tree_b_;
  SurfaceEdges edges_a_, edges_b_;
  SurfaceContactSet set_;
  Eigen::VectorXd start_a_, start_b_;  // positions at the step's start (correctGaps)
  Eigen::VectorXd end_a_, end_b_;
  Eigen::VectorXd normals_a_, normals_b_;  // surface node normals at the step's start
  std::vector<int> found_;
};

}  // namespace torsion
