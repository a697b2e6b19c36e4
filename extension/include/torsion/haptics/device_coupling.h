#pragma once
// What a haptic device holds in the world, as the HapticRuntime drives it (haptic_runtime.h):
// a hand plane (HandCoupling) or a rigid tool (ToolCoupling). Each substep of the world the
// runtime hands it the loop's newest HandCommand at two moments, and takes back the wrench the
// loop renders:
//   beforeRigidStep  before Bullet's rigid solve (FemSoftBodySolver::predictMotion): a tool's
//                    coupling must act on its body's velocity before Bullet moves it;
//   beforeFemStep    before the FEM step (solveConstraints): a hand grabs, moves, releases;
//   afterFemStep     after the substep, whether it succeeded or not: a tool gives back what it
//                    lent the step;
//   publish          after a successful substep: the wrench, the device pose it belongs to and
//                    the local stiffness K_h, in device units.
// Simulation thread only.

#include <cstdint>

#include "torsion/bullet/step_context.h"
#include "torsion/constraints/carried_nodes.h"
#include "torsion/device/device_types.h"
#include "torsion/result.h"

namespace torsion::haptics {

class DeviceCoupling {
 public:
  virtual ~DeviceCoupling() = default;
  virtual void beforeRigidStep(const device::HandCommand& /*command*/, const StepContext& /*ctx*/) {
  }
  /// An error is a warning of the runtime (a grab that found nothing to hold).
  virtual Status beforeFemStep(const device::HandCommand& /*command*/, const StepContext& /*ctx*/) {
    return Ok{};
  }
  virtual void afterFemStep(const StepContext& /*ctx*/, bool /*ok*/) {}
  virtual device::SimulationWrench publish(std::uint64_t step) = 0;
  /// The wrench of the last publish() in the world frame (what the device renders, before the
  /// mapping's scales and the loop's local model).
  virtual const Wrench& worldWrench() const = 0;
  /// Device poses refused because they were not finite or out of reach once mapped.
  virtual std::uint64_t rejectedPoses() const = 0;
};

}  // namespace torsion::haptics
