#pragma once
// Where the device's workspace sits in the world, and how its units scale: device pose (metres
// on the desk) <-> hand frame (metres in the scene); world wrench <-> device wrench. The device
// frame's origin and axes are `anchor` in the world; device positions are multiplied by
// `position_scale`. The wrench reaches the device rotated into the device frame and multiplied
// by `force_scale` / `torque_scale` (1: the user feels the simulated newtons).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

#include "torsion/constraints/carried_nodes.h"
#include "torsion/constraints/frame.h"
#include "torsion/device/device_types.h"

namespace torsion::haptics {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct DeviceMapping {
  Frame anchor;               ///< the world frame of the device's zero pose
  double position_scale = 1;  ///< world m per device m
  double force_scale = 1;     ///< device N per world N
  double torque_scale = 1;    ///< device N m per world N m

  /// m: a device pose mapped beyond this from the origin is refused (a packet may carry 1.7e308).
  static constexpr double kMaxReach = 1e6;

  Frame toWorld(const device::Pose& pose) const;
  /// toWorld(pose) when its origin is finite and within kMaxReach and its rotation finite (checked
  /// after the scale: a finite but enormous position overflows once scaled); else nullopt.
  std::optional<Frame> toWorldWithinReach(const device::Pose& pose) const;
  device::Pose toDevice(const Frame& frame) const;
  device::Wrench wrenchToDevice(const Wrench& world) const;
  /// dW/dpose (world, about the hand's origin) -> device units, row-major into out[36].
  void stiffnessToDevice(const Matrix6d& world, double out[36]) const;
};

/// The rotation vector (axis times angle, |angle| <= pi) of a unit quaternion.
Eigen::Vector3d rotationVector(const Eigen::Quaterniond& q);

}  // namespace torsion::haptics
