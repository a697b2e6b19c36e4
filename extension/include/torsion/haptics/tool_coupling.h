#pragma once
// A rigid tool held by a haptic device: a dynamic Bullet body of its own mass, pulled toward the
// device's pose by a 6-DoF spring-damper, the virtual coupling of Colgate et al. (1995) and
// Adams & Hannaford (1999). The tool stops at surfaces instead of passing into them, and the
// device renders the coupling's force. docs/haptics.md, "Tools".
//
// The coupling is integrated implicitly with the tool, inside each substep's solves. Before
// Bullet's rigid solve (beforeRigidStep), for step h, device goal (x_d, R_d) at the step's end,
// its velocity (v_d, w_d) and the tool's (m, I; x, v, R, w; external force and torque f, t):
//   (m + c) v' = m v + h (k (x_d - x) + b v_d + f),        c   = h (h k + b)
//   (I + c_r) w' = I w + h (k_r theta + b_r w_d + t),       c_r = h (h k_r + b_r),
// theta the rotation vector of R_d R^T. The tool enters the step with velocity (v', w') and, for
// the step only, mass m + c and inertia I + c_r (its forces folded into v', w'): that is the
// backward-Euler step of body and spring together, so Bullet's rigid solve and the FEM contact
// island push on the tool and its spring as one body, and the contact impulses balance the
// coupling force (at rest, exactly). afterFemStep gives the tool back its mass, inertia and
// forces and takes the coupling force at the step's end,
//   F = k (x_d - x) + b (v_d - v),   T = k_r theta + b_r (w_d - w),
// of which the device renders the reaction -(F + m g) (the tool's weight compensated unless
// `feel_weight`), about the device frame's origin.
//
// Between steps the loop predicts with K_h = -(K_c - K_c (K_c + K_e)^-1 K_c): the coupling K_c in
// series with the stiffness K_e of the tool's contacts: with rigid bodies, Bullet's manifolds (a
// touching point counts as a spring kRigidContactStiffness along its normal), so a rigid wall
// feels as stiff as the coupling at the loop's rate; with FEM bodies, each touching patch's normal
// stiffness from the body's step system (contact_stiffness.h), refreshed every
// `contact_stiffness_refresh_steps` steps. In free space K_h = 0.
// Simulation thread only.

#include <memory>
#include <unordered_map>

#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/constraints/carried_nodes.h"
#include "torsion/constraints/frame.h"
#include "torsion/haptics/contact_stiffness.h"
#include "torsion/haptics/device_coupling.h"
#include "torsion/haptics/device_mapping.h"

class btRigidBody;

namespace torsion::haptics {

struct ToolCouplingSettings {
  double stiffness = 1000;        ///< N/m, k
  double angular_stiffness = 10;  ///< N m/rad, k_r
  /// Damping as a fraction of critical for the tool's own mass and inertia:
  /// b = 2 zeta sqrt(k m), b_r = 2 zeta sqrt(k_r I_max).
  double damping_ratio = 1;
  /// N and N m: the spring's pull is capped here (a device far from a jammed tool cannot push it
  /// through what holds it with an unbounded force).
  double max_force = 100;
  double max_torque = 10;
  bool feel_weight = false;  ///< render the tool's weight too (false: the contacts only)
  /// K_e's FEM part every this many steps (one CG solve per touching body); 0: rigid contacts
  /// only.
  int contact_stiffness_refresh_steps = 5;
  double contact_stiffness_tolerance = 1e-3;  ///< relative CG tolerance of those solves
  /// Publish only K_h's passive part (device/passive_stiffness.h).
  bool passive_stiffness = true;

  Status validate() const;
};

class ToolCoupling : public DeviceCoupling {
 public:
  /// N/m: a touching rigid contact point in K_e, far stiffer than any coupling, so that K_h is
  /// the coupling's own stiffness along the contact normals.
  static constexpr double kRigidContactStiffness = 1e7;

  /// `tool` must be a dynamic body (mass > 0) of the world `solver` is attached to, and both must
  /// outlive the coupling (the solver's FEM bodies and the world's manifolds give K_e). The
  /// device's zero pose sits at mapping.anchor. Settings must be valid. The tool is kept awake (a
  /// sleeping body would not follow the device).
  static Result<std::unique_ptr<ToolCoupling>> create(btRigidBody& tool,
                                                      const FemSoftBodySolver& solver,
                                                      const DeviceMapping& mapping,
                                                      const ToolCouplingSettings& settings);

  void beforeRigidStep(const device::HandCommand& command, const StepContext& ctx) override;
  void afterFemStep(const StepContext& ctx, bool ok) override;
  device::SimulationWrench publish(std::uint64_t step) override;
  std::uint64_t rejectedPoses() const override { return rejected_poses_; }

  /// Parts carried with the tool (a grasper's jaws): their weight is compensated with its own
  /// unless `feel_weight`.
  void addCarriedMass(double kg) { carried_mass_ += kg; }
  /// The device's frame in the world: where the coupling pulls the tool.
  const Frame& goal() const { return goal_; }
  /// The coupling's pull on the tool at the last step's end (world, about the tool's centre).
  const Wrench& couplingWrench() const { return coupling_; }
  /// The rendered wrench of the last step, world frame: -(coupling + weight unless felt).
  const Wrench& worldWrench() const override { return world_wrench_; }
  /// K_h of the last publish(), world frame.
  const Matrix6d& worldStiffness() const { return world_stiffness_; }
  btRigidBody& tool() { return tool_; }
  const btRigidBody& tool() const { return tool_; }

 private:
  ToolCoupling(btRigidBody& tool, const FemSoftBodySolver& solver, const DeviceMapping& mapping,
               const ToolCouplingSettings& settings);
  /// The goal from a command; a dead device or a refused pose holds the last one.
  void takeGoal(const device::HandCommand& command);
  /// The stiffness of the tool's touching contacts with rigid bodies (world, about its centre).
  Matrix6d rigidContactStiffness() const;
  /// With FEM bodies: each touching patch's k_n along its normal through its centre.
  Matrix6d femContactStiffness();
  void restoreMass();

  btRigidBody& tool_;
  const FemSoftBodySolver& solver_;
  DeviceMapping mapping_;
  ToolCouplingSettings settings_;
  double mass_ = 0;          // the tool's own, kg
  double carried_mass_ = 0;  // kg, carried parts whose weight is compensated with it
  Eigen::Vector3d local_inertia_ = Eigen::Vector3d::Zero();  // its principal moments, kg m^2
  double linear_damping_ = 0, angular_damping_ = 0;          // b, b_r
  // The goal and its velocity over the step
  Frame goal_;
  Frame previous_goal_;
  bool have_previous_goal_ = false;
  Eigen::Vector3d goal_velocity_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d goal_angular_velocity_ = Eigen::Vector3d::Zero();
  device::Pose goal_pose_;
  std::uint64_t command_tick_ = 0;
  double command_time_ = 0;
  std::uint64_t rejected_poses_ = 0;
  // What the step borrowed: the tool's forces, and that its mass is swapped
  bool lent_ = false;
  Eigen::Vector3d saved_force_ = Eigen::Vector3d::Zero(), saved_torque_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d gravity_ = Eigen::Vector3d::Zero();
  // Results of the last step
  Wrench coupling_;
  Wrench world_wrench_;
  Matrix6d world_stiffness_ = Matrix6d::Zero();
  // K_e's FEM part: each touching body's patch stiffness, refreshed every few steps
  ContactStiffness contact_stiffness_;
  std::unordered_map<const FemBody*, double> patch_stiffness_;  // N/m
  int steps_since_refresh_ = 0;
};

}  // namespace torsion::haptics
