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
//   stage 4, the solve                       the contacts are rows of the body's contact island
//                                            (convexRows; bullet/island_step.h), solved with
//                                            everything it touches; takeConvexSolution takes the
//                                            answer back
//   after the step (finish)                  dynamic rigid bodies get their new velocities and
//                                            the pose correction dt (v_new - v_bullet);
//                                            multibodies their links' impulses
//
// Multibody links are partners like rigid bodies, with the multibody's effective mass at the link
// (multibody_partner.h). Anchored nodes (node_anchors.h) are contacts that stick for good.
//
// A node held by a hand or a node group is never moved by a contact: its row pushes a dynamic
// rigid body away and has nothing to do against static or kinematic ones.

#include <BulletDynamics/Dynamics/btRigidBody.h>
#include <BulletSoftBody/btSoftBody.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "torsion/checkpoint_stream.h"
#include "torsion/contact/face_contacts.h"
#include "torsion/contact/multibody_partner.h"
#include "torsion/contact/node_anchors.h"
#include "torsion/contact/rigid_partner.h"
#include "torsion/contact/solve/rigid_contact_group.h"
#include "torsion/fem/fem_model.h"
#include "torsion/solve/fem_state.h"
#include "torsion/solve/node_constraints.h"

namespace torsion::sap {
class JointLedger;  // solve/joint_ledger.h
struct ConvexRows;  // solve/convex_rows.h
struct SolvedBody;
struct SapReport;  // solve/sap_solver.h
}  // namespace torsion::sap

namespace torsion {

struct ContactSettings {
  /// Coulomb friction coefficient of the FEM body; a pair's is this times the rigid body's
  /// (Bullet's combination rule).
  double friction = 1.0;
};

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
  bool anchored = false;           ///< an anchor (node_anchors.h): sticks for good, gap = -drift
  State state = State::kInactive;  ///< after the solve
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
  int newton_iterations = 0;       ///< of the island's solves this step (0: no contact to solve)
  bool converged = true;           ///< the island's solve converged
  double normal_impulse = 0;       ///< N s, sum over contacts (>= 0)
  double max_penetration = 0;      ///< m, deepest node or face point inside a rigid body at the
                                   ///< step's start
                                   ///< (measured: the result of the previous step)
  double max_end_penetration = 0;  ///< m, deepest linearised end-of-step gap after the solve
};

/// What a RigidContactSolver's next step takes over from its last (its warm starts), with the
/// rigid objects by pointer: the active node contacts (state, impulse, plane) and the face rows'
/// features (normal impulse). Checkpoints store this (RigidContactSolver::save) instead of the
/// whole solver; it must list everything detect() reads from the last step.
struct CarriedContacts {
  struct Node {
    int node = -1;
    const btCollisionObject* object = nullptr;
    NodeContact::State state = NodeContact::State::kSlide;
    /// N s: the impulse it ended the last step with (the lagged friction bound).
    Eigen::Vector3d impulse = Eigen::Vector3d::Zero();
    /// The plane the contact was linearised on (its outward normal): detect() keeps it while the
    /// node stays over that face of the object.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  /// The convex solve's memory of a face row: the normal impulse of the
  /// rigid feature at `lever` of `object` (contact/solve/face_contact_rows.h).
  struct Feature {
    const btCollisionObject* object = nullptr;
    Eigen::Vector3d lever = Eigen::Vector3d::Zero();  ///< m, the feature point minus the com
    double normal_impulse = 0;                        ///< N s
  };
  std::vector<Node> nodes;
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
  /// After the step: velocities and pose corrections onto dynamic rigid bodies, impulses onto
  /// multibodies.
  void finish();

  /// The convex solve's rows of this step (contact/solve/convex_rows.h), the body's share of its
  /// island (bullet/island_step.h).
  sap::ConvexRows convexRows();
  /// The island's answer for those rows (`report` restricted to them, in their order; `bodies`:
  /// the rigid island bodies of rows.island), where finish(), detection's memory, the statistics
  /// and the checkpoints read it.
  void takeConvexSolution(const sap::ConvexRows& rows, const sap::SapReport& report,
                          const std::vector<sap::SolvedBody>& bodies);

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
  /// corner, edge and face rows (solve/face_contact_rows.h).
  const std::vector<FaceContact>& solvedFaceContacts() const { return solved_faces_; }
  /// Polyhedral partners' corner and edge contacts (FaceContactSet::featureContacts).
  const std::vector<FaceContact>& featureContacts() const { return faces_.featureContacts(); }
  const std::vector<RigidPartner>& partners() const { return partners_; }
  const ContactStepStats& stats() const { return stats_; }

  /// The warm starts the next step takes over (checkpoints: carried_contacts.cpp).
  CarriedContacts carriedContacts() const;
  /// Back to carried contacts: the next step starts as it did after carriedContacts(). The last
  /// step's contacts() then list them alone, without their geometry and impulses.
  void restoreCarriedContacts(const CarriedContacts& carried);
  /// The checkpoint's bytes of what the next step takes over: the friction setting and
  /// carriedContacts(), rigid objects by their index in the world (checkpoint_stream.h).
  void save(CheckpointWriter& out) const;
  /// Back to bytes of save(): the next step starts as it did after save(). Errors, changing
  /// nothing: bytes cut short, or values no save writes (a node out of range, an object not in
  /// the reader's world, a value not finite).
  Status restore(CheckpointReader& in);

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

  // The convex solve (rigid_contact_convex.cpp).
  /// s: how far ahead detection predicts a node's motion to choose its plane: the step plus its
  /// rows' dissipation time (a row engages at phi0 + (dt + tau_d) v_n < 0).
  double lookahead(double dt) const;
  /// The convex solve: whether the island takes `body`'s contacts with other rigid objects from
  /// Bullet this step (contact/solve/rigid_contact_rows.h); then it is never `supported`.
  bool islandTakesRigidContacts(btRigidBody& body) const;
  /// The convex solve, at detection: the rigid contacts of the dynamic partners and of the bodies
  /// touching them, taken from Bullet into rigid_group_; every body of the group becomes a
  /// dynamic partner.
  void takeRigidContacts();

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
  std::vector<Eigen::Vector3d> previous_impulse_;  // N s, the lagged friction bounds
  std::vector<Eigen::Vector3d> previous_normal_;   // the plane it was linearised on
  std::vector<int> previous_of_node_;              // per node: its index in previous_active_, or -1
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
  double dt_ = 0;
  ContactStepStats stats_;
};

}  // namespace torsion
