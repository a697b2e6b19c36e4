#pragma once
// Which device readings the haptic loop takes. A reading is refused when it is not a pose (a
// non-finite number, a quaternion whose norm is not 1), lies beyond any device's reach, or moves
// from the last accepted (alive) reading faster than a hand moves a device. A refused reading
// enters none of the loop's state (passivity observer, twist estimate, step blend, local model, the
// simulation's command): one glitch of 1e7 m would otherwise be booked as megajoules of energy
// generated at the port, which the passivity controller then tries to take back for as long as
// the hand holds on. The loop holds the last accepted reading in its place for at most
// `hold_time`; longer, the device counts as dead and its output fades (docs/haptics.md).

#include <string>

#include "torsion/device/device_types.h"

namespace torsion::device {

struct ReadingCheck {
  /// m from the device frame's origin. Desktop devices reach tens of centimetres; no device
  /// reaches 10 m, while a corrupted reading is typically far beyond it.
  double max_reach = 10;
  /// m/s of the motion since the last accepted reading. A hand's fastest reaches peak at a few
  /// m/s; 10 leaves a margin for a device's own noise and a late tick.
  double max_speed = 10;
  /// rad/s likewise: a wrist turns at up to about 20 rad/s.
  double max_angular_speed = 100;
  /// s a refused reading is replaced by the last accepted one (as a plug-in's late reading is):
  /// one glitch does not cut the force; a device that keeps sending nonsense is dead.
  double hold_time = 0.005;

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

/// True when `pose` is a pose: finite, unit quaternion (within 1e-3), within max_reach.
bool isPlausiblePose(const Pose& pose, const ReadingCheck& check);

/// True when moving from `from` to `to` in `elapsed` seconds is within the speed bounds.
/// `min_elapsed` (s, one loop period) floors the elapsed time, so two readings a hair apart are
/// not refused for a motion that spans a period.
bool isPlausibleMotion(const Pose& from, const Pose& to, double elapsed, double min_elapsed,
                       const ReadingCheck& check);

}  // namespace torsion::device
