#pragma once
// A two-jaw grasper held by a haptic device: a palm (a dynamic rigid body on the device's virtual
// coupling, tool_coupling.h) and two jaws (dynamic boxes) on prismatic joints along the palm's
// local x axis, one each side. While the device's button is held the joints' velocity motors
// close the jaws at `closing_speed` with at most `grip_force` each; released, they open. The jaws
// grip by friction: what they hold hangs on the joints, the palm and the coupling, so the device
// feels its weight. Every part is an ordinary Bullet body and joint, so contact with FEM bodies
// is solved in their island with the joints (docs/contact-solve.md, "Joints in the island").
// docs/haptics.md, "Tools". Simulation thread only.

#include <array>
#include <memory>

#include "torsion/haptics/tool_coupling.h"

class btDynamicsWorld;
class btSliderConstraint;

namespace torsion::haptics {

struct GrasperSettings {
  /// m, the gap between the jaws' inner faces when open; the jaws close until they meet.
  double opening = 0.1;
  double closing_speed = 0.05;  ///< m/s, each jaw's
  double grip_force = 20;       ///< N, each jaw's motor at most
  int button = 1;               ///< held: closed (1-32)

  Status validate() const;
};

class GrasperCoupling : public DeviceCoupling {
 public:
  /// `palm` and the two jaws must be dynamic bodies of the world `solver` is attached to, and
  /// outlive the coupling; the jaws start open, each `settings.opening / 2` plus its half width
  /// from the palm's centre plane along the palm's local x (jaws[0] on the -x side). The joints
  /// are added to the world here and removed by the destructor.
  static Result<std::unique_ptr<GrasperCoupling>> create(const FemSoftBodySolver& solver,
                                                         btRigidBody& palm,
                                                         std::array<btRigidBody*, 2> jaws,
                                                         const DeviceMapping& mapping,
                                                         const ToolCouplingSettings& coupling,
                                                         const GrasperSettings& settings);
  ~GrasperCoupling() override;
  GrasperCoupling(const GrasperCoupling&) = delete;
  GrasperCoupling& operator=(const GrasperCoupling&) = delete;

  void beforeRigidStep(const device::HandCommand& command, const StepContext& ctx) override;
  void afterFemStep(const StepContext& ctx, bool ok) override { palm_->afterFemStep(ctx, ok); }
  device::SimulationWrench publish(std::uint64_t step) override { return palm_->publish(step); }
  std::uint64_t rejectedPoses() const override { return palm_->rejectedPoses(); }
  const Wrench& worldWrench() const override { return palm_->worldWrench(); }

  /// The jaws are closing (the button was held at the last step).
  bool closing() const { return closing_; }
  /// m, the gap between the jaws' inner faces now.
  double gap() const;
  const ToolCoupling& palm() const { return *palm_; }

 private:
  GrasperCoupling(btDynamicsWorld& world, std::unique_ptr<ToolCoupling> palm,
                  std::array<btRigidBody*, 2> jaws, const GrasperSettings& settings);

  btDynamicsWorld& world_;
  std::unique_ptr<ToolCoupling> palm_;
  std::array<btRigidBody*, 2> jaws_;
  std::array<std::unique_ptr<btSliderConstraint>, 2> joints_;
  GrasperSettings settings_;
  std::array<double, 2> jaw_half_width_{};  // m, along the palm's x
  bool closing_ = false;
};

}  // namespace torsion::haptics
