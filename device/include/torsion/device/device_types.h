#pragma once
// Plain data exchanged between a haptic device, the 1 kHz loop and the simulation. Trivially
// copyable on purpose: these structs cross threads through lock-free buffers, so they hold no
// pointers and no heap memory. SI units throughout. This library knows nothing of Bullet or GL.

#include <cstdint>

namespace torsion::device {

struct Vec3 {
  double x = 0, y = 0, z = 0;
};

/// Unit quaternion, w first.
struct Quat {
  double w = 1, x = 0, y = 0, z = 0;
};

/// A 6-DoF pose: position in metres, orientation as a unit quaternion, in the device frame.
struct Pose {
  Vec3 position;
  Quat orientation;
};

/// Force (N) and torque (N m) the device should apply to the user's hand.
struct Wrench {
  Vec3 force;
  Vec3 torque;
};

/// What a device can physically do. Output beyond these is clamped before it is written.
struct DeviceLimits {
  double max_force = 0;   ///< N, largest force norm the device may render
  double max_torque = 0;  ///< N m, largest torque norm the device may render
  Vec3 workspace_min;     ///< m, reachable box of the end effector
  Vec3 workspace_max;
};

/// One reading of the device.
struct DeviceSample {
  /// s, loop clock of the reading (earlier than now when a device holds an old one)
  double time = 0;
  Pose pose;
  std::uint32_t buttons = 0;  ///< bit k set: button k+1 held (bit 0 is the report's button 1)
  bool alive = false;         ///< false when the device stopped answering
};

/// What the haptic loop hands the simulation every tick (device frame). Grab and release requests
/// are counters, not flags, so that a press between two simulation steps is never lost: the
/// simulation acts when a counter moved since it last looked.
struct HandCommand {
  std::uint64_t tick = 0;  ///< the loop's tick that wrote it
  double time = 0;         ///< s, loop clock
  Pose pose;
  bool alive = false;  ///< the device answered this tick
  /// Buttons held (bit k: button k+1), as last read from a live device (a grasper's jaws close
  /// while its button is held; a dead device's last buttons stand).
  std::uint32_t buttons = 0;
  std::uint32_t grab_requests = 0;     ///< button 1 presses so far (report section 5.4)
  std::uint32_t release_requests = 0;  ///< button 2 presses so far
};

/// What the simulation hands the haptic loop after each step (device frame and units). The loop
/// renders W = wrench + stiffness * (pose now - pose) between steps (docs/design.md section 4).
struct SimulationWrench {
  std::uint64_t step = 0;          ///< simulation step that produced it; 0: nothing published yet
  std::uint64_t command_tick = 0;  ///< HandCommand::tick of the pose the step used
  double command_time = 0;         ///< s, HandCommand::time of that pose (loop clock)
  bool grabbed = false;            ///< the hand holds a patch and force output is enabled
  Pose pose;                       ///< device pose the wrench belongs to
  Wrench wrench;                   ///< what the body pushes the hand with, N and N m
  /// 6x6 row-major dW/dpose at `pose`: rows (force, torque), columns (translation in m, rotation
  /// vector in rad). Units N/m, N/rad, N m/m, N m/rad. Zero when unknown.
  double stiffness[36] = {};
};

}  // namespace torsion::device
