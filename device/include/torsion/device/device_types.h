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
  double time = 0;  ///< s, monotonic clock of the reader
  Pose pose;
  std::uint32_t buttons = 0;  ///< bit k set: button k+1 held (bit 0 is the report's button 1)
  bool alive = false;         ///< false when the device stopped answering
};

}  // namespace torsion::device
