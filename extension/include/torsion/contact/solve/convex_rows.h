#pragma once
// One FEM body's share of a convex contact island (docs/contact-solve.md), as its contact solver
// hands it out and takes the answer back: its rows (nodes and faces against rigid objects, the
// rigid bodies' contacts and joints it took from Bullet), its rigid island bodies, and what an
// island made of several FEM bodies needs to merge shares (FemContactIslands): which object each
// rigid body is, and which rows two shares hold both. Also the island's solve with matched
// friction bounds and the solved twists, common to a lone body's solve and an island's.

#include <BulletCollision/CollisionDispatch/btCollisionObject.h>

#include <Eigen/Core>
#include <vector>

#include "torsion/contact/face_contacts.h"
#include "torsion/contact/rigid_partner.h"
#include "torsion/contact/solve/node_contact_rows.h"
#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap {

struct ConvexRows {
  /// Bodies 0 (this FEM body) and 1.. (its dynamic rigid partners), the rows on them.
  NodeContactIsland island;
  std::vector<FaceContact> faces;  ///< the face rows' contacts (island.row_face)
  /// Per row: its friction-bound group (a partner's rows together; a rigid-rigid row alone).
  std::vector<int> row_group;
  /// Per rigid island body (island body b + 1): its collision object and its twist at the step's
  /// start (the solve's warm start).
  std::vector<const btCollisionObject*> body_objects;
  std::vector<Vector6d> start_twists;
  /// Per row: null for this body's own contacts; for a row between rigid bodies that another
  /// FEM body of the island may hold too, what it stands for (the Bullet contact point, or the
  /// joint with row_key_index its row among the group's joint rows).
  std::vector<const void*> row_key;
  std::vector<int> row_key_index;
};

/// A dynamic rigid island body after the solve: its twist, and whether this share applies it to
/// the body (false: another FEM body of the island holds the same body and applies it).
struct SolvedBody {
  Vector6d twist = Vector6d::Zero();
  bool applies = true;
};

/// Solves `problem` from `x` (in: the warm start; out: the velocities), then again wherever a
/// group's lagged friction bounds and the solve's normal impulses disagree (below); returns the
/// last solve's report with the iterations of every round summed.
///
/// The lagged model bounds each row's friction by mu times its last normal impulse. Where that
/// impulse is far from the present one the bound is wrong for a step: a contact new to the solve
/// has none (a box landing on a slope slides freely: +12 % of Coulomb's distance on the soft
/// incline), and after an impact the bound is the impact's. Where a group's rows together carried
/// a normal impulse outside [1/1.1, 1.1] times the one the solve gave them, or its new rows
/// carried more than 1 % of it, each of its contact rows' bound becomes the impulse just found
/// and the island is solved again (at most twice): a fixed point of mu gamma_n for the groups
/// that need it.
/// `solver` solves every round with its settings (one solver: its workspace is sized once).
SapReport solveWithMatchedFrictionBounds(SapSolver& solver, SapProblem& problem,
                                         const std::vector<int>& row_group, Eigen::VectorXd& x);

/// The twists of rigid island bodies first_body.. (6 dofs each) after the solve: each one's
/// momentum plus the wrench of every row on it (J^T gamma), through its mass: its momentum
/// balance with the impulses the rows report exact (the optimality criterion alone leaves a
/// residual of 1e-6 of the momenta).
std::vector<Vector6d> solvedTwists(const SapProblem& problem, const SapReport& report,
                                   int first_body);

}  // namespace torsion::sap
