#pragma once
// The pure part of the SpaceMouse device: a 3Dconnexion cap reports how far it is pushed and
// twisted (spacenavd's counts, about +-350 at full deflection), not where it is. Like a joystick
// in rate mode, the reading is a velocity: the integrator turns the newest reading into a twist
// and integrates it into a pose, clamped to a workspace box. No libspnav here, so it is tested
// without a device (tests/device/spacemouse_integrator_test.cpp).

#include <string>

#include "torsion/device/device_types.h"

namespace torsion::device {

struct SpaceMouseSettings {
  double full_scale = 350;        ///< counts of a fully deflected cap (spacenavd's usual range)
  double max_linear_speed = 0.1;  ///< m/s at full deflection
  double max_angular_speed = 1;   ///< rad/s at full deflection
  int dead_zone = 8;              ///< |counts| up to this are zero: the cap never rests at 0
  double max_step = 0.05;         ///< s; a longer gap between reads integrates only this much
  Vec3 workspace_min{-0.2, -0.2, -0.2};  ///< m; the pose stays in this box
  Vec3 workspace_max{0.2, 0.2, 0.2};

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

/// One motion reading, spacenavd's axes and counts.
struct SpaceMouseReading {
  int translation[3] = {0, 0, 0};
  int rotation[3] = {0, 0, 0};
};

class SpaceMouseIntegrator {
 public:
  explicit SpaceMouseIntegrator(const SpaceMouseSettings& settings) : settings_(settings) {}

  /// The newest reading; it holds until the next (spacenavd sends readings only on change).
  void setReading(const SpaceMouseReading& reading) { reading_ = reading; }
  /// Integrates the held reading's twist from the previous call's time to `time` (s) and returns
  /// the pose. The first call only sets the clock.
  const Pose& advance(double time);
  const Pose& pose() const { return pose_; }

  /// The twist a reading commands: linear m/s and angular rad/s (fixed device frame).
  void twistOf(const SpaceMouseReading& reading, Vec3& linear, Vec3& angular) const;

 private:
  double speedFraction(int counts) const;

  SpaceMouseSettings settings_;
  SpaceMouseReading reading_;
  Pose pose_;
  double time_ = 0;
  bool started_ = false;
};

}  // namespace torsion::device
