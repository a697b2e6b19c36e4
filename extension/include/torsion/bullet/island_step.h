#pragma once
// One contact island's step (docs/contact-solve.md): FEM bodies that touch each other (or a lone
// body), with everything their contacts reach, solved as one convex problem. Owned by
// FemSoftBodySolver; simulation thread only. The caller drives every stage:
//
//   prepare   every body prepares its step (FemBody::prepare: node groups, forces, detection of
//             its rigid contacts and self-contact candidates, the stepper's system A v = b). A
//             body whose prepare fails (non-finite forces) leaves the island; its pairs sit the
//             step out.
//   rows      each body hands out its share of rows (RigidContactSolver::convexRows: nodes and
//             faces against rigid objects, anchors, the rigid bodies' contacts and joints it took
//             from Bullet), its self-contact candidates become rows on its own nodes, and the
//             pairs' candidates rows between two bodies (surface_contact_rows.h)
//   solve     one SAP problem holds every FEM body, every dynamic rigid body once, and the rows
//             (sap_solver.h); then, until nothing moves: the surface rows' gaps are moved onto the
//             true end-of-step surface of the solved motion, self-contact looks again along that
//             motion (new candidates become new rows), and the island is solved again from where
//             it stood
//   finish    every share takes its answer (impulses, states, the rigid bodies' twists), the
//             surface contacts their multipliers, and every body finishes its step
//             (FemBody::finish: integration, health, impulses onto Bullet's bodies)
//
// A lone body without rows solves its system alone (the stepper's CG or CHOLMOD); with
// self-contact on, it then looks along the solved motion and is solved again as an island when
// that motion meets its own surface. Everything runs serially in island order: the result is the
// same for any thread count.

#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/step_context.h"
#include "torsion/contact/body_pair_contact.h"
#include "torsion/contact/solve/sap_problem.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion {

/// A pair of touching bodies of the island: its contact and its bodies' places in the group.
struct IslandPair {
  BodyPairContact* contact = nullptr;
  int first = 0, second = 0;
};

/// The island's contacts between FEM bodies after its step.
struct IslandPairStats {
  int candidates = 0;  ///< node-triangle and edge-edge pairs
  int active = 0;      ///< pushing at the end of the step
  int sticking = 0;    ///< of which sticking
  int iterations = 0;  ///< Newton iterations of the island's solves
  bool converged = true;
  double normal_impulse = 0;       ///< N s, sum over active contacts
  double max_end_penetration = 0;  ///< m, deepest linearised end gap
  double gap_tolerance = 0;        ///< m, the largest tolerance of the island's pairs
};

/// What island steps keep from one to the next: storage, never results (a step gives the same
/// bits with a fresh workspace). The SAP problem's blocks and the solver's workspace (its
/// vectors, the preconditioner's matrices) are sized once instead of allocated and first touched
/// at every step. One per FemSoftBodySolver; islands use it one after the other, and the problem
/// is empty between them.
struct IslandWorkspace {
  sap::SapProblem problem;
  sap::SapSolver solver;
};

/// Steps `group` (bodies in the solver's order) with the candidates of `pairs` between them.
/// Reports an unconverged solve on the bodies (FemBody::noteContactNotConverged).
IslandPairStats stepIsland(const std::vector<FemBody*>& group, const std::vector<IslandPair>& pairs,
                           const StepContext& ctx, IslandWorkspace& workspace);

}  // namespace torsion
