#pragma once
// Pieces of the device tests' closed loops, in which a stand-in simulation (a spring, a push, the
// FEM cylinder) answers the haptic loop's newest command: the answer's bookkeeping, the simulated
// operator who grabs and twists the device, and the swing of the device's angle in a logged run.

#include <algorithm>
#include <cstdint>
#include <vector>

#include "simulated_arm.h"
#include "torsion/device/haptic_loop.h"

namespace torsion::device {

/// Simulation step `step`'s answer to command `c`: the command's tick and pose, grabbed while the
/// command's grab requests outnumber its releases; no wrench or stiffness yet.
inline SimulationWrench answerTo(const HandCommand& c, std::uint64_t step) {
  SimulationWrench w;
  w.step = step;
  w.command_tick = c.tick;
  w.grabbed = c.grab_requests > c.release_requests;
  w.pose = c.pose;
  return w;
}

/// An operator who presses the grab button at 10 ms and from 0.1 s turns the device about z by
/// `twist` (rad) over `twist_time` (s), holding it with `wrist_damping` (N m s/rad); the device
/// renders up to 3 N m.
inline simulated::SimulatedArmSettings twistingArm(double twist, double twist_time,
                                                   double wrist_damping) {
  simulated::SimulatedArmSettings arm;
  arm.intent = simulated::SimulatedArmSettings::Intent::kTwist;
  arm.intent_start = 0.1;
  arm.intent_time = twist_time;
  arm.intent_rate = twist / twist_time;
  arm.grab_time = 0.01;
  arm.max_torque = 3;
  arm.wrist_damping = wrist_damping;
  return arm;
}

/// Peak-to-peak of `values` over the samples whose `time` (s, same length) is in [from, to).
inline double peakToPeak(const std::vector<double>& time, const std::vector<double>& values,
                         double from, double to) {
  double lo = 1e300, hi = -1e300;
  for (size_t k = 0; k < time.size(); ++k) {
    if (time[k] < from || time[k] >= to) continue;
    lo = std::min(lo, values[k]);
    hi = std::max(hi, values[k]);
  }
  return hi - lo;
}

}  // namespace torsion::device
