#pragma once
// Face contacts as SAP rows (docs/contact-solve.md, "From detection to rows"): a rigid feature (a
// box's corner or a point of its edge) against the inside of a FEM surface triangle or edge
// (face_contacts.h, RigidContactSolver::faceContacts()), appended to a node-contact island.
//
// Side A is the rigid partner, side B the face point: FaceContact::normal points from the rigid
// surface to the face, so v_n > 0 separates. Per face contact, one row:
//
//   face point   nodeTerm(fem_body, node_j, w_j, R_c) for each of the triangle's nodes of
//                  non-zero barycentric weight w_j (an edge contact has two), R_c = contactFrame(n)
//   dynamic      + rigidPointTerm(partner's RigidBody, lever, -1, R_c)
//   prescribed   velocity_offset = -R_c (v + omega x lever), as for node rows
//
// mu the pair's coefficient, phi0 the face point's gap at the step's start, k and tau_d from
// RowDefaults, as for node rows.
//
// Lagged normal impulses are keyed by the rigid object and the rigid feature point (its lever,
// the point minus the centre of mass, world frame at the step's start), not by the triangle: a
// corner or edge sliding onto the neighbouring triangle is the same feature at the same lever, so
// it keeps its impulse (and its friction bound). Each remembered impulse goes to the one contact of
// the same object whose lever is nearest, within `match_radius` (the caller's choice: half the
// mesh spacing keeps neighbouring points of one edge apart), and impulses going to one contact
// add up: the total is conserved, so two triangles meeting at a corner do not both take the
// corner's impulse (which gave the sliding box +6 % friction). Levers in the world frame: a partner
// that turns by more than match_radius / |lever| in one step loses the match for that step (its
// face rows start without friction, as new contacts do).

#include <Eigen/Core>
#include <vector>

#include "torsion/contact/face_contacts.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/rigid_partner.h"
#include "torsion/contact/solve/node_contact_rows.h"
#include "torsion/contact/solve/sap_solver.h"

namespace torsion::sap {

/// A face row's next-step memory: the normal impulse of the rigid feature at `lever` of `object`.
using LaggedFaceImpulse = CarriedContacts::Feature;

/// The face contacts an island solve takes from detection: the corner and edge contacts of
/// polyhedral partners (boxes, convex hulls: query/feature_contacts.h) and the nearest-point
/// contacts of every other shape (spheres, capsules, triangle meshes: face_distance.h).
std::vector<FaceContact> islandFaceContacts(const RigidContactSolver& contacts);

/// Appends one row per face contact in `faces` to `island` (built by buildNodeContactIsland from
/// the same `partners`), its index in `faces` in island.row_face, with lagged normal impulses from
/// `lagged`, each given to the contact of nearest lever within `match_radius` (m).
void addFaceContactRows(NodeContactIsland& island, const std::vector<FaceContact>& faces,
                        const std::vector<RigidPartner>& partners, int fem_body,
                        const std::vector<LaggedFaceImpulse>& lagged, double match_radius,
                        const RowDefaults& defaults, double dt);

/// Adds to `impulses` (per partner, as partnerImpulses gives them) the wrenches of the face rows.
void addFacePartnerImpulses(const NodeContactIsland& island, const std::vector<FaceContact>& faces,
                            const SapReport& report, std::vector<Vector6d>& impulses);

/// The next step's lagged face impulses: per face row with gamma_n > 0, its object and lever.
std::vector<LaggedFaceImpulse> laggedFaceImpulses(const NodeContactIsland& island,
                                                  const std::vector<FaceContact>& faces,
                                                  const std::vector<RigidPartner>& partners,
                                                  const SapReport& report);

/// What the island's solve leaves detection for the next step (RigidContactSolver::
/// restoreCarriedContacts): the node rows with gamma_n > 0 as active contacts, with their normal
/// (detect() keeps a node's plane while the node stays over that face:
/// RigidContactSolver::keepPreviousPlane), state stick when |gamma_t| is inside the friction disk,
/// and impulse (world, N s, on the node). Without it every contact is new to detection, and a node
/// under a box's edge is linearised afresh each step on whichever of the two faces meeting there
/// is nearer: often the side face.
CarriedContacts carriedContacts(const NodeContactIsland& island,
                                const std::vector<NodeContact>& contacts,
                                const std::vector<RigidPartner>& partners, const SapReport& report);

}  // namespace torsion::sap
