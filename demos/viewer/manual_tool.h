#pragma once
// The tool `torsion view`'s manual input moves: a tool whose device is `manual`
// (device/manual_device.h). The viewer works in the world, the device in its own frame: the
// world frame the keys and Ctrl + drag ask for is turned into a device pose with the tool's
// DeviceMapping, and the tool's virtual coupling pulls the body there as it would toward a real
// device. G holds button 1 and U lets it go, so a grasper's jaws close and open.
// Simulation (GUI) thread; the device itself may be read by a haptic thread.

#include <string>

#include "scene_haptics.h"
#include "torsion/constraints/frame.h"

namespace torsion::viewer {

class ManualToolControl {
 public:
  /// The device starts at its zero pose: the tool's starting frame, no button held.
  explicit ManualToolControl(const scene::SceneHaptics::ManualTool& tool);

  const std::string& name() const { return tool_.name; }
  bool grasper() const { return tool_.grasper; }
  /// The world frame the device is asked to hold the tool at.
  const Frame& goal() const { return goal_; }
  /// Moves the device so that it holds the tool at `world`.
  void moveTo(const Frame& world);
  /// Holds (true) or lets go of (false) button 1.
  void holdButton(bool held);
  bool buttonHeld() const { return held_; }
  /// What the device was last asked to render (device frame, after the loop's safety rules).
  Wrench rendered() const;

 private:
  scene::SceneHaptics::ManualTool tool_;
  Frame goal_;
  bool held_ = false;
};

}  // namespace torsion::viewer
