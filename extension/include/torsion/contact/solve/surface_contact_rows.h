#pragma once
// Contacts between two FEM bodies as SAP rows (docs/contact-solve.md, "FEM bodies in one
// island"): a pair's candidates (body_pair_contact.h: a surface node against the other body's
// triangle, or an edge across an edge) become rows of the island that holds both bodies, so a
// soft block on a soft incline, or a stack of soft bodies, is solved once with everything that
// touches it.
//
// A candidate c joins four nodes with weights beta (node against triangle: 1, -w_a, -w_b, -w_c;
// edge against edge: 1 - s, s, -(1 - t), -t), the relative velocity u = sum_k beta_k v_k and the
// triangle's (or the edges') outward normal n at the step's start, from the triangle's body
// towards the node. Its row:
//
//   terms        nodeTerm(body of node k, node k, beta_k, R_c), R_c = contactFrame(n)
//   gap          c.gap - c.target_gap: the solve drives the end gap to the contact's thickness
//   mu           the pair's friction; k, tau_d the near-rigid defaults (RowDefaults)
//   lagged       n . Lambda, Lambda the impulse on the node the pair kept from the last step
//
// Since sum beta_k = 0 the row's impulse exchanges momentum exactly between the two bodies. After
// the solve each candidate keeps its impulse (world, on the node) as its multiplier and its
// state, which the pair keeps as the next step's lagged impulse (SurfaceContactSet::warmStarts).

#include <vector>

#include "torsion/contact/solve/contact_row.h"
#include "torsion/contact/solve/node_contact_rows.h"
#include "torsion/contact/solve/sap_solver.h"
#include "torsion/contact/surface_contact_set.h"

namespace torsion::sap {

/// Appends one row per candidate of `set` (a pair's: its nodes [0, node_count_a) are island
/// body `body_a`'s, the rest `body_b`'s, less node_count_a) to `rows`; returns the first row's
/// index.
int addSurfaceContactRows(std::vector<ContactRow>& rows, const SurfaceContactSet& set,
                          int node_count_a, int body_a, int body_b, const RowDefaults& defaults,
                          double dt);

/// The solve's answer onto the candidates of `set` (candidate c is row rows[c] of `problem` and
/// `report`, as addSurfaceContactRows made it, its gap as last set): impulse on the node (world)
/// as the multiplier, the state, and the end gap less the thickness.
void takeSurfaceContactImpulses(SurfaceContactSet& set, const SapProblem& problem,
                                const std::vector<int>& rows, const SapReport& report, double dt);

}  // namespace torsion::sap
