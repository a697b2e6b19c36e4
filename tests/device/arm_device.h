#pragma once
// A HapticDevice over the simulated device and operator (device/plugins/simulated_device/
// simulated_arm.h): what the example plug-in wraps in the C ABI, linked directly for tests.

#include <string>

#include "simulated_arm.h"
#include "torsion/device/haptic_device.h"

namespace torsion::device {

class ArmDevice : public HapticDevice {
 public:
  explicit ArmDevice(const simulated::SimulatedArmSettings& s) : arm_(s) {}
  std::string name() const override { return "arm"; }
  DeviceLimits limits() const override {
    DeviceLimits l;
    l.max_force = arm_.settings().max_force;
    l.max_torque = arm_.settings().max_torque;
    return l;
  }
  DeviceSample read(double time) override {
    const simulated::ArmState s = arm_.read(time);
    DeviceSample out;
    out.time = time;
    out.pose.position = {s.position[0], s.position[1], s.position[2]};
    out.pose.orientation = {s.orientation[0], s.orientation[1], s.orientation[2], s.orientation[3]};
    out.buttons = s.buttons;
    out.alive = true;
    return out;
  }
  void write(const Wrench& w) override {
    const double v[6] = {w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z};
    arm_.write(v);
  }
  simulated::SimulatedArm& arm() { return arm_; }

 private:
  simulated::SimulatedArm arm_;
};

}  // namespace torsion::device
