#pragma once
// Two-way contact between one FEM body and Bullet's rigid bodies, resolved inside the body's
// implicit step (docs/contact.md). Touched only by the simulation thread.
//
// Per step:
//   stage 2 (Bullet's collision detection)  the broadphase pairs (soft body, collision object)
//                                            reach addCandidate through
//                                            FemSoftBodySolver::processCollision
//   stage 4, before the solve (detect)       each candidate object, at its pose after Bullet's
//                                            rigid integration, is queried against the body's
//                                            node tree (Bullet's DBVT); surface nodes near it get
//                                            an exact signed distance (shape_distance.h), and
//                                            surface triangles near it the shape's distance
//                                            (face_distance.h): face contacts hold rigid
//                                            features that fall between nodes
//   stage 4, the solve (solve)               velocity-level unilateral constraints, one per node,
//                                            in the projected CG: a node in contact is prescribed
//                                            along the normal (sliding) or fully (sticking) to
//                                            the rigid body's surface velocity; a dynamic rigid
//                                            body's 6 velocities join the CG unknowns, so the
//                                            exchange of momentum is implicit and exact. An
//                                            active-set loop releases pulling contacts, adds
//                                            penetrating ones and switches stick/slide by
//                                            Coulomb's law (friction coefficient per pair).
//                                            Face contacts join the same solves as an augmented
//                                            Lagrangian (face_contacts.h).
//   after the step (finish)                  dynamic rigid bodies get their new velocities and
//                                            the pose correction dt (v_new - v_bullet);
//                                            multibodies their links' impulses
//
// Multibody links are partners like rigid bodies, with the multibody's effective mass at the link
// (multibody_partner.h). Anchored nodes (node_anchors.h) are contacts that stick for good.
//
// A node held by a hand or a node group is never moved by a contact: it pushes a dynamic rigid
// body away (a sequential-impulse pass on the rigid body alone) and ignores static or kinematic
// ones.

#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletSoftBody/btSoftBody.h>

#include <Eigen/Core>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "torsion/contact/coulomb_problem.h"
#include "torsion/contact/delassus_condensation.h"
#include "torsion/contact/face_contacts.h"
#include "torsion/contact/multibody_partner.h"
#include "torsion/contact/node_anchors.h"
#include "torsion/contact/rigid_partner.h"
#include "torsion/contact/solve/rigid_contact_group.h"
#include "torsion/fem/fem_model.h"
#include "torsion/solve/cholmod_solver.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/projected_cg.h"
#include "torsion/solve/system_operator.h"

namespace torsion::sap {
class JointLedger;  // solve/joint_ledger.h
struct ConvexRows;  // solve/convex_rows.h
struct SolvedBody;
struct SapReport;  // solve/sap_solver.h
}  // namespace torsion::sap

namespace torsion {

struct ContactSettings {
  /// m: an inactive contact whose predicted end-of-step gap is below -this joins the active set.
  double activation_tolerance = 1e-6;
  /// Active-set / friction iterations per step (each one CG solve, warm-started).
  int max_active_set_iterations = 30;
  /// Sequential-impulse sweeps for held nodes against dynamic rigid bodies.
  int held_iterations = 20;
  /// Coulomb friction coefficient of the FEM body; a pair's is this times the rigid body's
  /// (Bullet's combination rule).
  double friction = 1.0;
  /// Face contacts (face_contacts.h): the augmented Lagrangian's penalty rho, in units of the
  /// face point's effective mass from the system's diagonal blocks. Larger closes the gap in fewer
  /// solves but slows each CG solve.
  double face_penalty = 20;
  /// m: face contacts iterate until every active one's end-of-step gap is within this (the
  /// stated penetration tolerance of a rigid feature between nodes).
  double face_gap_tolerance = 1e-5;
  /// How stick, slide and separation are decided (docs/contact.md, "Coulomb's law solved in
  /// contact space"). kContactSpace factorises the step's matrix, condenses it onto the contacts
  /// and solves Coulomb's law there for all of them at once (coulomb_problem.h): the states are
  /// consistent with the impulses by construction, and a rigid box holds at the stick/slip
  /// threshold and slides as Coulomb says over soft and stiff, coarse and fine slabs (a step that
  /// does not converge falls back to the active set: coulomb_fallback). kActiveSet switches states
  /// between CG solves by rules: right for nodes on static or kinematic geometry, each contact
  /// on its own, but a dynamic rigid body's contacts share its motion and there the rules let a
  /// box creep 3 mm in 1 s 1 deg below the friction angle of a soft slab. kAuto (the default)
  /// takes contact space in the steps where a dynamic rigid body touches the FEM body and the
  /// active set otherwise, so a large body on the ground does not pay for a factorisation each
  /// step. A body in FEM-FEM contact (whose pair penalties the factor does not hold) always uses
  /// the active set.
  /// kConvex: one convex solve (SAP, docs/contact-solve.md) of the body with its dynamic rigid
  /// partners and the rigid bodies touching them, node and face contacts, anchors and the rigid
  /// bodies' contacts (contact/solve/rigid_contact_rows.h) as rows; a body in FEM-FEM contact is
  /// driven by the island's solve around it.
  enum class FrictionSolve { kActiveSet, kContactSpace, kAuto, kConvex };
  FrictionSolve friction_solve = FrictionSolve::kConvex;
  /// m/s: the contact-space solve iterates until every contact satisfies Coulomb's law to this;
  /// a step that ends its sweeps within coulomb_acceptable counts as converged.
  double coulomb_tolerance = 1e-7;
  double coulomb_acceptable = 1e-6;
  /// The contact-space solve's contact compliance, as a part of the Delassus operator's largest
  /// diagonal entry (the most mobile contact's velocity per unit impulse): every contact yields
  /// by that much per unit impulse (constraint force mixing). It makes W definite where redundant
  /// contacts leave it nearly singular (a rigid box on a stiff slab), so that every step's
  /// Coulomb problem converges; at a step's impulses it lets a contact sink or creep by about
  /// 1e-4 of the velocity it cancels, under 0.1 um per step at dt = 0.01 (docs/contact.md).
  double coulomb_compliance = 1e-4;
  /// Projected Gauss-Seidel sweeps at most per step; a step that needs more is reported as not
  /// converged (ContactStepStats::active_set_converged).
  int coulomb_max_sweeps = 3000;
  /// A step whose contact-space solve does not converge is solved again by the active set
  /// (ContactStepStats::coulomb_fell_back); off, the unconverged impulses are kept.
  bool coulomb_fallback = true;
};

/// The names scene files and Python use for ContactSettings::FrictionSolve: "auto",
/// "active_set", "contact_space", "convex".
const char* frictionSolveName(ContactSettings::FrictionSolve solve);
/// The solve `name` names, or nullopt.
std::optional<ContactSettings::FrictionSolve> frictionSolveFromName(const std::string& name);

/// One node in contact with one rigid object during a step.
struct NodeContact {
  enum class State { kInactive, kSlide, kStick };
  int node = -1;
  int partner = -1;        ///< index into partners()
  Eigen::Vector3d normal;  ///< unit, world, out of the rigid body: the linearisation's plane
  double gap = 0;          ///< m, signed distance to that plane at the start of the step
  double distance = 0;     ///< m, signed distance to the shape at the start of the step
  Eigen::Vector3d lever;   ///< m, contact point minus centre of mass (start of step)
  double friction = 0;     ///< pair coefficient
  bool held = false;       ///< the node is prescribed (hand, node group)
  /// Held by the supporting plane facing the soft surface, not the nearest feature: the rigid
  /// body is sweeping over the node this step (a sliding box's leading edge).
  bool swept = false;
  bool anchored = false;  ///< an anchor (node_anchors.h): sticks for good, gap = -drift
  State state = State::kInactive;
  int releases = 0;  ///< times released this step (anti-cycling: once; a side contact twice)
  int slips = 0;     ///< stick-to-slide switches this step (anti-cycling: at most two)
  int friction_refinements = 0;  ///< sliding friction updates this step that reopened the loop
  Eigen::Vector3d friction_impulse = Eigen::Vector3d::Zero();  ///< N s on the node (sliding)
  /// kg, sliding: the friction's resistance to a slip across its direction in the next solve
  /// (its linearisation in the slip; RigidContactSolver::setSlipResistances).
  Eigen::Matrix3d slip_resistance = Eigen::Matrix3d::Zero();
  Eigen::Vector3d impulse = Eigen::Vector3d::Zero();  ///< N s, total the rigid body gave the node
  double normal_impulse = 0;                          ///< N s, impulse . normal
};

/// The tangential velocity (m/s) of node velocity `node_velocity` relative to the rigid surface
/// point of contact `c` when its body moves at `rigid_velocity`.
inline Eigen::Vector3d tangentialSlip(const NodeContact& c, const Eigen::Vector3d& node_velocity,
                                      const Vector6d& rigid_velocity) {
  const Eigen::Vector3d relative = node_velocity - pointVelocity(rigid_velocity, c.lever);
  return relative - c.normal * c.normal.dot(relative);
}

struct ContactStepStats {
  int candidates = 0;       ///< surface nodes within the detection margin
  int face_candidates = 0;  ///< surface triangles (or edges) with a face contact candidate
  int active = 0;           ///< node and face contacts active at the end of the step
  int face_active = 0;      ///< of which face contacts
  int sticking = 0;         ///< of which sticking
  /// Contact points between rigid bodies solved in this body's island (the convex solve:
  /// contact/solve/rigid_contact_rows.h); not counted above.
  int rigid_rows = 0;
  int active_set_iterations = 0;  ///< CG solves this step
  bool active_set_converged = true;
  double normal_impulse = 0;       ///< N s, sum over contacts (>= 0)
  double max_penetration = 0;      ///< m, deepest node or face point inside a rigid body at the
                                   ///< step's start
                                   ///< (measured: the result of the previous step)
  double max_end_penetration = 0;  ///< m, deepest linearised end-of-step gap after the solve
  int coulomb_sweeps = 0;          ///< contact-space solve: Gauss-Seidel sweeps this step
  double coulomb_residual = 0;     ///< m/s, its largest violation of Coulomb's law at the end
  bool coulomb_fell_back = false;  ///< the contact-space solve did not converge: active set used
  bool in_contact_space = false;   ///< the step took the contact-space solve (fallback or not)
};

/// What a RigidContactSolver's next step takes over from its last (its warm starts), with the
/// rigid objects by pointer: the active node contacts (their stick or slide state) and the face
/// contacts (state, multiplier). Checkpoints that leave memory (bullet/checkpoint_io.h) store this
/// instead of the whole solver; it must list everything detect() reads from the last step.
struct CarriedContacts {
  struct Node {
    int node = -1;
    const btCollisionObject* object = nullptr;
    NodeContact::State state = NodeContact::State::kSlide;
    /// N s: the contact-space solve's warm start (the active set starts from the states alone).
    Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
    /// The plane the contact was linearised on (its outward normal): detect() keeps it while the
    /// node stays over that face of the object.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  struct Face {
    std::array<int, 3> key{};
    const btCollisionObject* object = nullptr;
    FaceContact::State state = FaceContact::State::kSlide;
    Eigen::Vector3d multiplier = Eigen::Vector3d::Zero();
    int stalls = 0;
  };
  /// The convex solve's memory of a face row (FrictionSolve::kConvex): the normal impulse of the
  /// rigid feature at `lever` of `object` (contact/solve/face_contact_rows.h).
  struct Feature {
    const btCollisionObject* object = nullptr;
    Eigen::Vector3d lever = Eigen::Vector3d::Zero();  ///< m, the feature point minus the com
    double normal_impulse = 0;                        ///< N s
  };
  std::vector<Node> nodes;
  std::vector<Face> faces;
  std::vector<Feature> features;
};

class RigidContactSolver {
 public:
  RigidContactSolver(std::shared_ptr<const FemModel> model, btSoftBody* soft_body);

  ContactSettings& settings() { return settings_; }
  /// Live material edit (FemBody::setMaterial): the same mesh, new masses.
  void replaceModel(std::shared_ptr<const FemModel> model) { model_ = std::move(model); }
  const ContactSettings& settings() const { return settings_; }

  /// Stage 1: forgets last step's candidates.
  void beginStep(double dt);
  /// Stage 2: a broadphase pair with `object`.
  void addCandidate(const btCollisionObject* object);
  /// Stage 4, before the solve: narrow phase. `constraints` holds the node groups' prescriptions
  /// (held nodes); `joints` the world's joints this substep (null: none), which the convex solve
  /// takes with the rigid bodies it takes and updates at finish(). Returns whether any node is
  /// near a rigid object.
  bool detect(const FemState& state, const NodeConstraints& constraints, double dt,
              sap::JointLedger* joints = nullptr);
  /// The linear solve of the step with contacts, on the stepper's prepared system
  /// (ImplicitStepper::prepared(); FemBody::solveContacts).
  LinearSolveReport solve(const SystemOperator& op, const NodeConstraints& constraints,
                          const Eigen::VectorXd& b, const SolverSettings& settings,
                          Eigen::VectorXd& v);
  /// After the step: velocities and pose corrections onto dynamic rigid bodies, impulses onto
  /// multibodies.
  void finish();

  /// The convex solve's rows of this step (contact/solve/convex_rows.h), for the body's own solve
  /// or an island of several FEM bodies (FemContactIslands).
  sap::ConvexRows convexRows();
  /// The island's answer for those rows (`report` restricted to them, in their order; `bodies`:
  /// the rigid island bodies of rows.island), where finish(), detection's memory, the statistics
  /// and the checkpoints read it.
  void takeConvexSolution(const sap::ConvexRows& rows, const sap::SapReport& report,
                          const std::vector<sap::SolvedBody>& bodies);

  // ---- in an island of touching FEM bodies (contact/island_contact.h) ----
  // A body whose rigid partners are all prescribed (static, kinematic, or supported by Bullet's
  // ground) has node contacts that are plain node constraints of its system: the island's joint
  // CG takes them (rigid_contact_island.cpp), and the active set runs between its solves.
  /// Whether this step's contacts can join an island's joint solve: no dynamic partner, no
  /// multibody link, no face contact (those need this solver's reduced system).
  bool joinsIsland() const;
  /// Before the island's first solve: `base` holds the body's own prescriptions (kept by address
  /// until endIslandSolve).
  void beginIslandSolve(const NodeConstraints& base);
  /// The active node contacts as prescriptions on top of base's, into `out` (stick: the rigid
  /// surface's velocity; slide: its normal speed), and `b` plus the sliding contacts' friction
  /// impulses into `b_friction`.
  void islandConstraints(const Eigen::VectorXd& b, NodeConstraints& out,
                         Eigen::VectorXd& b_friction) const;
  /// After an island solve: `v` the body's velocities, `impulses` (3n) the constraint impulses on
  /// its nodes (A v - b_friction less the pair contacts' impulses). Runs the active set; returns
  /// whether any contact changed (another solve is needed).
  bool updateIslandActiveSet(const Eigen::VectorXd& v, const Eigen::VectorXd& impulses);
  /// After the island's last solve: impulses, statistics and end gaps, as solve() ends.
  void endIslandSolve(const Eigen::VectorXd& v, bool active_set_converged);

  /// Anchors `nodes` (at their positions in `state`) to `object` (node_anchors.h). Returns the
  /// anchor's id.
  int addAnchor(const btCollisionObject* object, std::vector<int> nodes, const FemState& state) {
    return anchors_.add(object, std::move(nodes), state);
  }
  void removeAnchor(int anchor) { anchors_.remove(anchor); }
  const NodeAnchors& anchors() const { return anchors_; }

  const std::vector<NodeContact>& contacts() const { return contacts_; }
  const std::vector<FaceContact>& faceContacts() const { return faces_.contacts(); }
  /// The face contacts the last solve used, with their states and impulses: the convex solve's
  /// corner, edge and face rows (solve/face_contact_rows.h), else faceContacts().
  const std::vector<FaceContact>& solvedFaceContacts() const {
    return settings_.friction_solve == ContactSettings::FrictionSolve::kConvex ? solved_faces_
                                                                               : faces_.contacts();
  }
  /// Polyhedral partners' corner and edge contacts (FaceContactSet::featureContacts).
  const std::vector<FaceContact>& featureContacts() const { return faces_.featureContacts(); }
  const std::vector<RigidPartner>& partners() const { return partners_; }
  const ContactStepStats& stats() const { return stats_; }

  /// The warm starts the next step takes over (checkpoints: carried_contacts.cpp).
  CarriedContacts carriedContacts() const;
  /// Back to carried contacts: the next step starts as it did after carriedContacts(). The last
  /// step's contacts() then list them alone, without their geometry and impulses.
  void restoreCarriedContacts(const CarriedContacts& carried);

 private:
  // detect's stages (rigid_contact_detection.cpp).
  void rememberActiveContacts();
  void forgetLastStep(double dt);
  void findContacts(const FemState& state, const NodeConstraints& constraints, double dt);
  void addNodeContact(const FemState& state, const NodeConstraints& constraints,
                      const btCollisionObject& object, const btTransform& transform, int node,
                      double reach, double lookahead_time);
  void addAnchorContacts(const FemState& state, const NodeConstraints& constraints);
  void dropUntouchedPartners();
  void warmStartActiveSet();
  void recordDetectionStats();
  int partnerIndex(const btCollisionObject* object);
  void chooseSupportPlane(const btCollisionShape& shape, const btTransform& transform,
                          const FemState& state, int node, const Eigen::Vector3d& into_surface,
                          double dt, NodeContact& c) const;
  /// Whether contact `c` (found as `nearest`) would rather be linearised on the supporting plane
  /// facing `into` (a unit direction into the soft surface): over the look-ahead `dt`, with the
  /// node's velocity relative to the rigid point, the plane leaves a larger end gap than the
  /// nearest feature's and than a plane `c` took before. Then `c` takes the plane.
  bool takeFacingPlane(const btCollisionShape& shape, const btTransform& transform,
                       const Eigen::Vector3d& x, const Eigen::Vector3d& into,
                       const Eigen::Vector3d& relative_velocity, double dt,
                       const NodeContact& nearest, NodeContact& c) const;
  void keepPreviousPlane(const btCollisionShape& shape, const btTransform& transform,
                         const Eigen::Vector3d& x, const Eigen::Vector3d& into_surface,
                         const btCollisionObject& object, NodeContact& c) const;
  btTransform startPoseOf(const btCollisionObject& object) const;
  /// Per node, whether it is anchored to `object` (empty when none is).
  std::vector<char> gluedTo(const btCollisionObject& object) const;
  void recordAnchorStartPoses();  // node_anchors.cpp

  // solve's stages (rigid_contact.cpp; the reduced system in rigid_contact_reduced_system.cpp).
  void numberRigidUnknowns();
  void warmStart(const Eigen::VectorXd& v);
  void setFacePenalties(const SystemOperator& op);
  void markDeterminedFaces();
  void assembleRightHandSide(const SystemOperator& op, const Eigen::VectorXd& b);
  void projectWarmStart();
  void buildPreconditioner(const SystemOperator& op);
  LinearSolveReport conjugateGradient(const SystemOperator& op, const Eigen::VectorXd& reduced_rhs,
                                      const SolverSettings& settings, Eigen::VectorXd& q);
  void accumulate(const LinearSolveReport& r, LinearSolveReport& total);
  /// v, the rigid velocities and the node constraints' impulses (product_) from the solution q_.
  void recoverSolution(const SystemOperator& op, Eigen::VectorXd& v);
  /// Node and face contact states after a solve; whether any changed (another solve is needed).
  bool updateContactStates(const Eigen::VectorXd& v);
  /// The node and face contact states (and sliding frictions) the solve just done used, before
  /// updateContactStates changes them; restoreSolvedStates() brings them back.
  void rememberSolvedStates();
  void restoreSolvedStates();
  void collectImpulses();
  void solveHeld(const Eigen::VectorXd& v, double dt);  // rigid_contact_held.cpp

  // The convex solve (rigid_contact_convex.cpp).
  LinearSolveReport solveConvex(const SystemOperator& op, const NodeConstraints& constraints,
                                const Eigen::VectorXd& b, Eigen::VectorXd& v);
  /// s: how far ahead detection predicts a node's motion to choose its plane: the step, and for
  /// the convex solve the step plus its rows' dissipation time (a row engages at
  /// phi0 + (dt + tau_d) v_n < 0).
  double lookahead(double dt) const;
  /// The convex solve: whether the island takes `body`'s contacts with other rigid objects from
  /// Bullet this step (contact/solve/rigid_contact_rows.h); then it is never `supported`.
  bool islandTakesRigidContacts(btRigidBody& body) const;
  /// The convex solve, at detection: the rigid contacts of the dynamic partners and of the bodies
  /// touching them, taken from Bullet into rigid_group_; every body of the group becomes a
  /// dynamic partner.
  void takeRigidContacts();
  void measureEndGaps(const Eigen::VectorXd& v);

  // The reduced system q = (u, V) (rigid_contact_reduced_system.cpp).
  void expand(const Eigen::VectorXd& q, Eigen::VectorXd& v) const;
  void contract(const Eigen::VectorXd& y, const Eigen::VectorXd& rigid_part,
                Eigen::VectorXd& q) const;
  void applyOperator(const SystemOperator& op, const Eigen::VectorXd& q, Eigen::VectorXd& out);
  /// The sliding node contacts' slip_resistance terms of the operator, for reduced unknowns `q`
  /// and their node velocities `v` (expand(q)).
  void addSlipResistance(const Eigen::VectorXd& q, const Eigen::VectorXd& v,
                         Eigen::VectorXd& node_out, Eigen::VectorXd& rigid_out) const;
  void precondition(const Eigen::VectorXd& r, Eigen::VectorXd& z) const;

  // The solve in contact space (rigid_contact_coulomb.cpp).
  /// One contact of the contact-space problem: a node (weights (1, 0, 0)) or a face point.
  struct CoulombRow {
    int node_contact = -1;  ///< index into contacts_, or -1
    int face_contact = -1;  ///< index into faces_.contacts(), or -1
    std::array<int, 3> nodes{-1, -1, -1};
    Eigen::Vector3d weights = Eigen::Vector3d::Zero();
    int partner = -1;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d lever = Eigen::Vector3d::Zero();
    double gap = 0;
    double friction = 0;
    bool bilateral = false;
  };

  bool solvesInContactSpace(const SystemOperator& op) const;
  LinearSolveReport solveInContactSpace(const SystemOperator& op,
                                        const NodeConstraints& constraints,
                                        const Eigen::VectorXd& b, Eigen::VectorXd& v);
  void gatherCoulombRows();
  /// Factorises the step's constrained matrix (lower triangle); false if not SPD or not finite.
  bool factoriseContactSystem(const Eigen::SparseMatrix<double>& lower);
  /// unit_impulses_ = S G^T for the selected rows.
  void buildUnitImpulses(const NodeConstraints& constraints);
  /// Solves Coulomb's problem on the selected rows from `warm` (every row's impulse): impulses_
  /// (every row's, zero for the others), contact_forces_, the velocities `v` and the partners'.
  CoulombReport solveSelectedRows(const NodeConstraints& constraints, const Eigen::VectorXd& warm,
                                  Eigen::VectorXd& v);
  /// The row's end gap rate with node velocities `v` and its partner's velocity `rigid`.
  double normalVelocity(const CoulombRow& row, const Eigen::VectorXd& v,
                        const Eigen::Matrix<double, 6, 1>& rigid) const;
  void warmStartCoulomb();
  /// Each contact's state and impulse from the solved impulses (and product_ for
  /// collectImpulses()).
  void recordCoulombStates();

  // The active set (rigid_contact_active_set.cpp).
  /// `p`: the node constraints' impulses (Coulomb's bounds: each scaled by its partner's
  /// friction_share).
  bool updateActiveSet(const Eigen::VectorXd& v, const Eigen::VectorXd& p, double dt);
  /// Each partner's friction_share from the solve just done (node impulses in product_).
  void measureFrictionShares();
  /// After the active set's update: each sliding node contact's slip_resistance from the slip of
  /// the solve just done.
  void setSlipResistances(const Eigen::VectorXd& v);

  std::shared_ptr<const FemModel> model_;
  btSoftBody* soft_body_;
  ContactSettings settings_;
  std::vector<char> surface_;
  std::vector<const btCollisionObject*> candidates_;
  std::vector<RigidPartner> partners_;
  MultibodyLinks links_;
  NodeAnchors anchors_;
  std::vector<NodeContact> contacts_;
  FaceContactSet faces_;
  std::vector<int> node_contact_;  // per node: index into contacts_ (free nodes only) or -1
  std::vector<std::pair<int, const btCollisionObject*>> previous_active_;  // (node, object)
  std::vector<NodeContact::State> previous_state_;
  std::vector<Eigen::Vector3d> previous_impulse_;  // N s, the contact-space warm start
  std::vector<Eigen::Vector3d> previous_normal_;   // the plane it was linearised on
  std::vector<int> previous_of_node_;              // per node: its index in previous_active_, or -1
  std::vector<std::pair<NodeContact::State, Eigen::Vector3d>> solved_states_;
  std::vector<FaceContact::State> solved_face_states_;
  std::vector<const btCollisionObject*> previous_sliding_;  // bodies sliding at the last step's end
  std::vector<CarriedContacts::Feature>
      lagged_features_;               // the convex solve's face rows, last step
  double feature_match_radius_ = -1;  // m, set at the first convex solve (the rest mesh's)
  // The convex solve's rigid contacts this step (detect to finish; pointers into Bullet's
  // manifolds, dropped at finish) and the last solve's impulse per point, written back at finish.
  std::vector<FaceContact> solved_faces_;  // the convex solve's face rows, last solve
  sap::RigidContactGroup rigid_group_;
  sap::JointLedger* joints_ = nullptr;  // this step's (detect's argument; dropped at finish)
  std::vector<Eigen::Vector3d> rigid_impulses_;
  std::vector<double> joint_impulses_;  // per joint row of rigid_group_, written back at finish
  const NodeConstraints* base_ = nullptr;
  double dt_ = 0;
  int dynamic_count_ = 0;
  ContactStepStats stats_;

  // Solve workspace.
  std::vector<Eigen::Matrix3d> block_inverse_;
  std::vector<Eigen::Matrix<double, 6, 6>> rigid_inverse_;
  Eigen::VectorXd v_c_, scratch_, product_, r_, reduced_rhs_, q_, rigid_scratch_, b_solve_;
  Eigen::VectorXd b_friction_;  // b plus the sliding node contacts' friction impulses
  Eigen::VectorXd rigid_rhs_;   // the rigid unknowns' part of the right-hand side
  PcgScratch cg_;

  // Contact-space workspace. A copy of the solver (a checkpoint) starts with a fresh one.
  // The factor is simplicial (no BLAS, no supernodes): the condensation needs its L itself, and
  // the bodies in contact are small enough that supernodes do not pay (measured: CHOLMOD's
  // supernodal factor and dense solves took 77 % of a contact-space step on the 441-node slab).
  using Factor = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower>;
  struct FactorWorkspace {
    std::unique_ptr<CholmodSolver> assembler = std::make_unique<CholmodSolver>();
    std::unique_ptr<Factor> factor = std::make_unique<Factor>();
    Eigen::Index rows = -1, entries = -1;  // the pattern the factor analysed
    FactorWorkspace() = default;
    FactorWorkspace(const FactorWorkspace& /*other*/) : FactorWorkspace() {}
    FactorWorkspace& operator=(const FactorWorkspace& /*other*/) { return *this; }
    ~FactorWorkspace() = default;
  };
  FactorWorkspace factorisation_;
  std::vector<CoulombRow> rows_;
  std::vector<int> selected_;  // the rows in this solve's problem (indices into rows_)
  std::vector<int> node_row_;  // gatherCoulombRows(): each node's row, or -1 (kept capacity)
  static constexpr int kMaxRowRounds = 8;
  static constexpr double kFaceOnNode = 0.9;   // gatherCoulombRows()
  Eigen::SparseMatrix<double> unit_impulses_;  // 3n x 3m: S G^T, node forces per unit impulse
  DelassusCondensation condensation_;          // W_soft = (L^-1 P S G^T)^T (L^-1 P S G^T)
  CoulombProblem coulomb_;
  Eigen::VectorXd impulses_, contact_velocity_;
  Eigen::VectorXd contact_forces_;     // 3n: S G^T r, the solved impulses' node forces
  Eigen::VectorXd v_free_;             // 3n: the step's velocities without contact
  Eigen::VectorXd fallback_velocity_;  // 3n: the solve's given velocities, kept for a fallback
  Eigen::VectorXd cold_start_, cold_velocity_;  // the retry from zero impulses
};

}  // namespace torsion
