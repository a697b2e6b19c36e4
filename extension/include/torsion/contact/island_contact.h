#pragma once
// One step's linear solve of an island: FEM bodies joined by contacts between them
// (body_pair_contact.h), each body keeping its own system A_i v_i = b_i and its own solve (CG,
// or its rigid-contact / self-contact solve), coupled by the pairs' augmented Lagrangian
// (docs/contact.md, "Contact between FEM bodies"). Touched only by the simulation thread.
//
// Per step, with the multipliers Lambda of every pair contact (warm-started from the last step),
// and B = rho I (sticking) or rho n n^T + k_t (I - n n^T) (sliding: friction implicit,
// SurfaceContactSet::operatorBlock), one of two paths:
//   joint       (no body brings a solve of its own) every body's velocities are one vector, the
//               pairs' whole term beta_k beta_l B couples them, one projected CG per update.
//               A body's node contacts with prescribed rigid partners (the ground) join it as
//               node constraints (RigidContactSolver::islandConstraints), their active set run
//               after each solve on the impulses the joint system leaves on them
//   sweep       (a body with self-contact, or rigid contacts needing the rigid solver's reduced
//               system) bodies in island order: body i solves its system plus the contacts'
//               penalty on its own nodes (PairContactTerm), with right-hand side b_i +
//               beta_k (Lambda - rho n g/dt - B u_other), u_other from the other bodies' latest
//               velocities (block Gauss-Seidel on the island's augmented system); then a closing
//               solve per body with the penalty off and the impulses fixed at Lambda, so that
//               body and partner get exactly opposite impulses
//   update      after each solve: Uzawa's projection of Lambda - rho h on Coulomb's cone for
//               every contact (SurfaceContactSet::update); repeated until no contact (pair or
//               rigid) changes state and every end gap is within the tolerance, or max_iterations
//               (reported). The end gaps are measured on the velocities the bodies keep.
// Everything runs serially in island order: the result is the same for any thread count.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "torsion/contact/body_pair_contact.h"
#include "torsion/contact/rigid_contact.h"
#include "torsion/solve/added_operator_term.h"
#include "torsion/solve/node_constraints.h"
#include "torsion/solve/projected_cg.h"
#include "torsion/solve/solver_settings.h"
#include "torsion/solve/system_operator.h"

namespace torsion {

/// The pair contacts' penalty on one body's own nodes, beta_k beta_l B for the contacts'
/// nodes k, l on this body (the rest of each constraint enters the right-hand side).
class PairContactTerm final : public AddedOperatorTerm {
 public:
  struct Side {
    const SurfaceContactSet* set = nullptr;
    int first = 0;  ///< this body's first node in the pair's index space
    int count = 0;  ///< this body's node count
  };
  void clear() { sides_.clear(); }
  void addSide(Side side) { sides_.push_back(side); }
  /// While suspended the term adds nothing (penalties from A alone; the closing solve).
  void setSuspended(bool suspended) { suspended_ = suspended; }

  void addProduct(const Eigen::VectorXd& y, Eigen::VectorXd& out) const override;
  void addDiagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const override;

 private:
  std::vector<Side> sides_;
  bool suspended_ = false;
};

struct IslandContactStats {
  int candidates = 0;  ///< pair contacts this step
  int active = 0;      ///< pushing at the end of the step
  int sticking = 0;    ///< of which sticking
  int iterations = 0;  ///< Uzawa updates (sweeps over the island) this step
  bool converged = true;
  double normal_impulse = 0;       ///< N s, sum over active contacts
  double max_end_penetration = 0;  ///< m, deepest linearised end gap after the closing solve
  double gap_tolerance = 0;        ///< m, the largest tolerance of the island's pairs
};

class IslandContactSolve {
 public:
  /// A body's own linear solve (its rigid-contact or self-contact solve, or plain CG when empty).
  using BodySolve = std::function<LinearSolveReport(const SystemOperator&, const NodeConstraints&,
                                                    const Eigen::VectorXd&, const SolverSettings&,
                                                    Eigen::VectorXd&)>;
  /// What one body brings to the island solve: its prepared system (ImplicitStepper::prepare).
  struct Body {
    const SystemOperator* op = nullptr;
    const NodeConstraints* constraints = nullptr;
    const Eigen::VectorXd* b = nullptr;
    const SolverSettings* settings = nullptr;
    Eigen::VectorXd* v = nullptr;  ///< warm start on entry, v' on return
    BodySolve solve;
    /// Its node contacts with prescribed rigid partners (ground, kinematic bodies), when they
    /// join the joint solve (RigidContactSolver::joinsIsland); then `solve` is empty. Not owned.
    RigidContactSolver* rigid = nullptr;
    PairContactTerm* term = nullptr;  ///< in op's added term (not owned)
    LinearSolveReport report;         ///< out: the body's solves, summed
    bool present = false;             ///< prepared its step (else its pairs sit this step out)
  };
  struct Pair {
    BodyPairContact* contact = nullptr;
    int first = 0, second = 0;  ///< indices into the bodies
  };

  /// Runs the sweeps, updates and the closing solve (above). `max_iterations`, `penalty_factor`
  /// from the pairs' settings (the first pair's).
  IslandContactStats solve(std::vector<Body>& bodies, const std::vector<Pair>& pairs, double dt);

 private:
  // rhs += the pair contacts' right-hand side on body `i`'s nodes (penalty part unless `closing`).
  void addRightHandSide(const std::vector<Body>& bodies, const std::vector<Pair>& pairs, size_t i,
                        double dt, bool closing, Eigen::VectorXd& rhs) const;
  // The pair's velocities (a's, then b's).
  void pairVelocities(const std::vector<Body>& bodies, const Pair& pair, Eigen::VectorXd& v) const;
  LinearSolveReport solveBody(Body& body, size_t i, const Eigen::VectorXd& rhs);
  // The joint path: every body's velocities one vector, the pairs' whole augmented term coupling
  // them, one projected CG (bodies without solves of their own). v' into the bodies' v.
  void jointSolve(std::vector<Body>& bodies, const std::vector<const Pair*>& live, double dt,
                  bool& broke);
  // The Gauss-Seidel path (a body with rigid contacts or self-contact keeps its own solve).
  // Returns whether settled; `moved`: m, the largest node motion change from the last sweep.
  void sweep(std::vector<Body>& bodies, const std::vector<Pair>& pairs, double dt, bool& broke,
             double& moved);
  // The pair terms' product over the joint vector (offsets: each body's first component).
  void addJointProduct(const std::vector<const Pair*>& live, const Eigen::VectorXd& y,
                       Eigen::VectorXd& out) const;
  // The joint path with rigid contacts: each such body's constraints and right-hand side with its
  // active node contacts (rebuilt before every joint solve).
  void prepareRigidContacts(std::vector<Body>& bodies);
  // Their active sets on the impulses of the last joint solve; whether any contact changed.
  bool updateRigidContacts(std::vector<Body>& bodies);
  const NodeConstraints& constraintsOf(const std::vector<Body>& bodies, size_t i) const {
    return bodies[i].rigid != nullptr ? rigid_constraints_[i] : *bodies[i].constraints;
  }
  const Eigen::VectorXd& rightHandSideOf(const std::vector<Body>& bodies, size_t i) const {
    return bodies[i].rigid != nullptr ? rigid_b_[i] : *bodies[i].b;
  }

  std::vector<ProjectedCg> cg_;  // plain solves, one per body (their workspaces)
  std::vector<int> offsets_;     // joint path: each body's first component (-1: absent)
  std::vector<Eigen::Matrix3d> joint_inverse_;
  Eigen::VectorXd joint_b_, joint_v_, joint_r_, joint_q_, joint_c_;
  Eigen::VectorXd joint_impulse_;                   // A v - b of the last joint solve, unfiltered
  std::vector<NodeConstraints> rigid_constraints_;  // per body with `rigid`
  std::vector<Eigen::VectorXd> rigid_b_;
  PcgScratch joint_scratch_;
  std::vector<std::vector<Eigen::Matrix3d>> blocks_;
  std::vector<Eigen::Matrix3d> pair_blocks_;
  Eigen::VectorXd rhs_, pair_v_, previous_v_;
  std::vector<Eigen::VectorXd> best_v_;                     // safeguard: the best round's
  std::vector<std::vector<SurfaceContact>> best_contacts_;  // velocities and multipliers
};

}  // namespace torsion
