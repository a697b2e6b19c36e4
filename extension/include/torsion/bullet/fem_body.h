#pragma once
// One corotational FEM body living in a Bullet world. It owns its FEM state, its implicit
// stepper and its node groups, and mirrors its nodes into a btSoftBody so Bullet's broadphase and
// soft-rigid collision detection see it. Touched only by the simulation thread.

#include <BulletSoftBody/btSoftBody.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#include <string>
#include <vector>

#include "torsion/bullet/step_context.h"
#include "torsion/constraints/carried_nodes.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/contact/self_contact.h"
#include "torsion/contact/solve/fem_island_body.h"
#include "torsion/fem/fem_model.h"
#include "torsion/mesh/input_numbering.h"
#include "torsion/result.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion {

/// Everything a body needs to go on from a moment as it went on then (FemBody::checkpoint).
struct FemBodyCheckpoint {
  std::shared_ptr<const FemModel> model;  ///< the material then (live edits are undone too)
  FemState state;
  Eigen::VectorXd external_forces;
  ImplicitStepper::Memory stepper;
  std::vector<CarriedNodes> groups;  ///< node groups then (hands: see Hand::checkpoint)
  /// The contact solvers' memory as bytes (checkpoint_stream.h): RigidContactSolver::save, then,
  /// with self-contact on, its multipliers (SurfaceContactSet::save). A file holds these bytes.
  std::string contacts;
  bool self_contact = false;  ///< self-contact was on
  SelfContactSettings self_contact_settings;
  StepReport last_report;
};

class FemBody {
 public:
  /// `world_objects`: the collision objects of the world the body is in (checkpoints name rigid
  /// objects by their index there).
  /// `input_numbering`: how the body's numbers map to those of the mesh it was made of.
  FemBody(std::string name, std::shared_ptr<const FemModel> model, const SolverSettings& settings,
          const Parallel& parallel, btSoftBodyWorldInfo& world_info,
          const btCollisionObjectArray& world_objects, InputNumbering input_numbering = {});
  ~FemBody();
  FemBody(const FemBody&) = delete;
  FemBody& operator=(const FemBody&) = delete;

  const std::string& name() const { return name_; }
  const FemModel& model() const { return *model_; }
  /// The model, shared (contact between FEM bodies keeps the meshes it detects on).
  std::shared_ptr<const FemModel> modelPointer() const { return model_; }
  const FemState& state() const { return state_; }
  btSoftBody* softBody() { return soft_body_.get(); }
  /// How the body's node and tet numbers (those of model(), state(), softBody() and every
  /// function here) map to the mesh given to FemWorld::addBody (identity unless it renumbered).
  const InputNumbering& inputNumbering() const { return input_numbering_; }
  /// model().mesh() in the input's numbering (itself when the numbering is the identity).
  const TetMesh& inputMesh() const {
    return input_numbering_.identity() ? model_->mesh() : *input_numbering_.inputMesh();
  }
  /// state()'s positions and velocities (3n) in the input's numbering: state()'s own when the
  /// numbering is the identity, else a copy kept current as Bullet's nodes are (after every step
  /// that did not fail, a velocity set, a restore), at the same addresses.
  const Eigen::VectorXd& inputPositions() const {
    return input_numbering_.identity() ? state_.positions : input_positions_;
  }
  const Eigen::VectorXd& inputVelocities() const {
    return input_numbering_.identity() ? state_.velocities : input_velocities_;
  }

  /// Adds a group of nodes carried rigidly by `motion` (a constant frame fixes them). Returns its
  /// index. p_hat is captured from the nodes' current positions and motion(now).
  int carryNodes(std::string group_name, std::vector<int> nodes, FrameMotion motion, double now);
  /// Frees the group's nodes (its index stays reserved and reports zero wrench).
  void releaseGroup(int group);
  /// Carries group `group` along `motion` from the next step on (CarriedNodes::setMotion): a held
  /// or scripted group becomes driven by whoever supplies the frames. A released group stays free.
  void setGroupMotion(int group, FrameMotion motion);
  const std::vector<std::unique_ptr<CarriedNodes>>& groups() const { return groups_; }

  /// The wrench the body exerts on group `group` at the end of the last step, about `point`.
  Wrench groupWrench(int group, const Eigen::Vector3d& point);

  /// Anchors `nodes` to `object` for good, two ways (docs/contact.md, "Anchors"): each node keeps
  /// the offset it has now in the object's frame, moves with it and pulls on it inside the same
  /// implicit solve. `object` is a btRigidBody (dynamic, kinematic or static) or a multibody link
  /// collider (btMultiBodyLinkCollider); it must stay in the world while anchored. A node held by
  /// a hand or a node group follows that instead. Returns the anchor's id for removeAnchor().
  /// Errors: a null object, an empty list, a node out of range, anchored already, or listed twice.
  Result<int> anchorNodes(std::vector<int> nodes, btCollisionObject* object);
  /// Frees an anchor's nodes (its id stays reserved). Errors: an unknown or removed anchor.
  Status removeAnchor(int anchor);
  /// The ids of the anchors that tie nodes to `object` now (empty: none).
  std::vector<int> anchorsOn(const btCollisionObject* object) const;
  /// Forgets `object`, which is leaving the world: the contact warm starts with it are dropped
  /// (the others are kept, as a checkpoint restore keeps them) and Bullet's contact list of the
  /// btSoftBody is cleared, so nothing the next step or a checkpoint reads points to it. Call it
  /// before the object is deleted; an object anchored to (anchorsOn) must not leave.
  void forgetObject(const btCollisionObject* object);

  /// Sets every node's velocity (m/s), e.g. an initial velocity before the first step. Errors
  /// (nothing set): a velocity that is not finite.
  Status setVelocity(const Eigen::Vector3d& velocity);
  /// Sets every node's velocity to a rigid motion: `linear` (m/s) for the centre of mass (lumped
  /// node masses, current positions) plus a spin `angular` (rad/s, axis times rate) about it,
  /// v_i = linear + angular x (x_i - c). The body's momentum is then M linear, its angular
  /// momentum about c is I_c angular (I_c: the lumped inertia of the current shape).
  /// Errors (nothing set): a velocity that is not finite.
  Status setRigidVelocity(const Eigen::Vector3d& linear, const Eigen::Vector3d& angular);

  /// External forces on the nodes besides gravity (which the body takes from its world each
  /// step, m_i g), N, 3n: they stay applied every step until changed. Errors: wrong size,
  /// non-finite values ("body 'cyl': external force on node 12 is not finite").
  Status setExternalForces(const Eigen::VectorXd& forces);
  /// One node's external force (N), kept until changed; node must be in [0, nodeCount()).
  Status setNodeForce(int node, const Eigen::Vector3d& force);
  /// The external forces besides gravity, N, 3n.
  const Eigen::VectorXd& externalForces() const { return external_forces_; }

  /// Live edit between steps (the viewer's E, nu, damping keys): the body goes on from its
  /// current state (positions, velocities, rotations, held groups, contacts) with `material`.
  /// Rest data are recomputed for the same mesh; the lumped masses, and with them the gravity
  /// forces, follow a new density. groupWrench() keeps reporting the last step as it was taken
  /// until the next step. Errors: an invalid material ("material: poisson_ratio = 0.5: ..."),
  /// and then nothing changes. References from model() taken before the call are stale after it.
  Status setMaterial(const Material& material);

  // ---- called by FemSoftBodySolver, in this order, each step ----
  /// Bullet's predictor: m_q = x_n, m_x = x_n + dt v_n, bounds and node tree refreshed, contacts
  /// cleared, so Bullet's collision detection runs on this step's motion. `for_contact` false
  /// (FemSoftBodySolver: the body is the world's only collision object and has no anchor, so
  /// nothing can touch it this step) leaves the node tree, which only contact detection reads, as
  /// it is; the first step for contact refits it (a function of the nodes and dt alone, so the
  /// tree is the one an every-step refresh gives).
  void predict(double dt, bool for_contact = true);
  /// Bullet's end of the step: node normals and bounds.
  void refreshSurface();
  // ---- the step in stages, driven by the body's contact island (bullet/island_step.h) ----
  /// Up to the linear solve: the node groups' prescriptions, this step's forces (external + m_i g),
  /// contact detection (rigid, self), the stepper's prepare(). `touches_fem_bodies`: the body is
  /// in an island with other FEM bodies. False when the step ended there (non-finite forces, or a
  /// hyperelastic body (Material::law) that touches anything: its Newton step has no contact
  /// solve; lastReport() says why; the state untouched; no finish()).
  bool prepare(const StepContext& ctx, bool touches_fem_bodies = false);
  /// The prepared step's system: operator, constraints (the groups' and anchors'), b, warm start.
  PreparedSystem preparedSystem() { return stepper_.prepared(); }
  /// The prepared step as an island body (contact/solve/fem_island_body.h): this step's b and
  /// the operator's blocks. One object from step to step, for its storage (its coarse space's).
  sap::FemIslandBody& islandBody();
  /// Whether this step found rigid objects near the body (its contact rows, anchors included).
  bool touchesRigid() const { return rigid_contact_; }
  /// The prepared step's solve without contact (the stepper's CG, CHOLMOD or Newton): v' into
  /// preparedSystem().v.
  LinearSolveReport solveAlone() { return stepper_.solve(); }
  /// After the solve: the stepper's finish() with v' = `velocities` (3n) and `solve` (the solve's
  /// report), the self-contact warning, impulses onto rigid bodies, the btSoftBody written back.
  const StepReport& finish(const Eigen::Ref<const Eigen::VectorXd>& velocities,
                           const LinearSolveReport& solve);

  const StepReport& lastReport() const { return last_report_; }

  /// A copy of the body's state and everything its next step reads (warm starts, node groups,
  /// contact multipliers), to go back to with restore(): the continuation is then bit for bit
  /// the one that followed checkpoint(), given the same world around it.
  FemBodyCheckpoint checkpoint();
  /// Back to `checkpoint` (taken from this body, or read by readCheckpoint: its contact bytes
  /// pass checkRestore). The btSoftBody mirror follows at once.
  void restore(const FemBodyCheckpoint& checkpoint);
  /// Whether the contact bytes of `checkpoint` read for this body, read as restore() reads them
  /// (onto scratch solvers: nothing changes). Errors name the body and the part that does not.
  Status checkRestore(const FemBodyCheckpoint& checkpoint) const;
  /// Contact with rigid bodies (docs/contact.md): candidates, settings, last step's contacts.
  RigidContactSolver& contacts() { return *contacts_; }
  const RigidContactSolver& contacts() const { return *contacts_; }
  ImplicitStepper& stepper() { return stepper_; }

  /// Self-contact (docs/contact.md, "Self-contact"): from the next step on, the body's surface
  /// nodes are kept out of its own surface triangles, with Coulomb friction, inside its implicit
  /// step. Errors: invalid settings (and then nothing changes).
  Status enableSelfContact(const SelfContactSettings& settings);
  void disableSelfContact();
  /// The self-contact solver (its last step's contacts and statistics), or nullptr when off.
  const SelfContactSolver* selfContact() const { return self_contact_.get(); }
  SelfContactSolver* selfContact() { return self_contact_.get(); }

  /// Marks the last step's report as not converged in contact (a warning, unless the step was
  /// already worse) and appends `what` to its message.
  void noteContactNotConverged(const std::string& what);

 private:
  void writeBack();
  /// Reads the contact bytes of `checkpoint` onto `rigid` and, with self-contact on in it, onto
  /// `self` (restore() and checkRestore() alike).
  Status readContacts(const FemBodyCheckpoint& checkpoint, RigidContactSolver& rigid,
                      SurfaceContactSet* self) const;

  std::string name_;
  std::shared_ptr<const FemModel> model_;
  FemState state_;
  const Parallel& parallel_;  // the world's threads (self-contact searches on them)
  ImplicitStepper stepper_;
  NodeConstraints constraints_;
  Eigen::VectorXd external_forces_;  // N, 3n, the user's (setExternalForces)
  Eigen::VectorXd step_forces_;      // N, 3n, this step's: external_forces_ + m_i g
  std::vector<std::unique_ptr<CarriedNodes>> groups_;
  std::unique_ptr<btSoftBody> soft_body_;
  const btCollisionObjectArray& world_objects_;
  InputNumbering input_numbering_;
  Eigen::VectorXd input_positions_, input_velocities_;  // inputPositions(), unless identity
  std::unique_ptr<RigidContactSolver> contacts_;
  std::unique_ptr<SelfContactSolver> self_contact_;
  std::unique_ptr<sap::FemIslandBody> island_body_;  // islandBody()'s
  bool rigid_contact_ = false;  // this step found nodes near rigid bodies (prepare)
  StepReport last_report_;
};

}  // namespace torsion
