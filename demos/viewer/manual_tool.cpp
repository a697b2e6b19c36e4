#include "manual_tool.h"

namespace torsion::viewer {

ManualToolControl::ManualToolControl(const scene::SceneHaptics::ManualTool& tool)
    : tool_(tool), goal_(tool.mapping.anchor) {
  tool_.device->setPose(tool_.mapping.toDevice(goal_));
  tool_.device->setButtons(0);
}

void ManualToolControl::moveTo(const Frame& world) {
  goal_ = world;
  tool_.device->setPose(tool_.mapping.toDevice(goal_));
}

void ManualToolControl::holdButton(bool held) {
  held_ = held;
  tool_.device->setButtons(held ? 0x1u : 0x0u);  // bit 0: button 1
}

Wrench ManualToolControl::rendered() const {
  const device::Wrench w = tool_.device->lastWritten();
  Wrench out;
  out.force = Eigen::Vector3d(w.force.x, w.force.y, w.force.z);
  out.torque = Eigen::Vector3d(w.torque.x, w.torque.y, w.torque.z);
  return out;
}

}  // namespace torsion::viewer
