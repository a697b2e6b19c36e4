#include "torsion/device/scripted_device.h"

#include <cmath>
#include <utility>

namespace torsion::device {

ScriptedDevice::ScriptedDevice(Trajectory trajectory, DeviceLimits limits, std::string name)
    : trajectory_(std::move(trajectory)), limits_(limits), name_(std::move(name)) {}

DeviceSample ScriptedDevice::read(double time) {
  if (std::isnan(start_time_)) start_time_ = time;
  const double t = std::min(time - start_time_, death_time_);
  DeviceSample sample;
  sample.time = time;
  sample.pose = trajectory_.poseAt(t);
  sample.buttons = trajectory_.buttonsAt(t);
  sample.alive = time - start_time_ < death_time_;
  return sample;
}

void ScriptedDevice::write(const Wrench& wrench) {
  last_written_ = wrench;
  ++writes_;
}

bool ScriptedDevice::finished(double time) const {
  return !std::isnan(start_time_) && time - start_time_ >= trajectory_.duration();
}

DeviceLimits defaultDeviceLimits() {
  DeviceLimits l;
  l.max_force = 30;
  l.max_torque = 3;
  l.workspace_min = {-0.2, -0.2, -0.2};
  l.workspace_max = {0.2, 0.2, 0.2};
  return l;
}

}  // namespace torsion::device
