#pragma once
// A scripted device trajectory: poses (device frame) and held buttons as functions of time.
// Built from keyframes or from piecewise constant-velocity motions; both end up as keyframes
// (positions interpolated linearly, orientations by slerp, held before the first and after the
// last). The file format is in docs/haptic-devices.md; assets/trajectories/figure_6_7.json is the
// report's Figure 6.7 sequence.

#include <cstdint>
#include <string>
#include <vector>

#include "torsion/device/device_types.h"
#include "torsion/device/loaded.h"

namespace torsion::device {

struct TrajectoryKeyframe {
  double time = 0;  ///< s
  Pose pose;
};

/// From `time` on, these buttons are held (bit k: button k+1).
struct ButtonEvent {
  double time = 0;
  std::uint32_t held = 0;
};

class Trajectory {
 public:
  Trajectory() = default;
  /// Keyframe times must increase strictly; button event times must not decrease.
  Trajectory(std::vector<TrajectoryKeyframe> keyframes, std::vector<ButtonEvent> buttons);

  Pose poseAt(double time) const;
  std::uint32_t buttonsAt(double time) const;
  /// Time of the last keyframe or button event, s.
  double duration() const;
  const std::vector<TrajectoryKeyframe>& keyframes() const { return keyframes_; }
  /// The same motion played `speed` times faster (keyframe and button times divided by it).
  /// `speed` must be positive.
  Trajectory playedAt(double speed) const;

 private:
  std::vector<TrajectoryKeyframe> keyframes_;
  std::vector<ButtonEvent> buttons_;
};

/// One constant-velocity piece: for `duration` seconds the device translates at
/// `linear_velocity` (m/s) and turns about its own centre at `angular_velocity` (rad/s, fixed
/// device frame).
struct MotionSegment {
  double duration = 0;
  Vec3 linear_velocity;
  Vec3 angular_velocity;
};

/// Keyframes for segments played one after the other from `start` at time 0 (long rotations
/// are split so that every keyframe interval turns by less than pi).
std::vector<TrajectoryKeyframe> keyframesFromSegments(const Pose& start,
                                                      const std::vector<MotionSegment>& segments);

/// Parses a trajectory file (JSON). Errors name the file and the key.
Loaded<Trajectory> parseTrajectory(const std::string& json_text, const std::string& source);
Loaded<Trajectory> loadTrajectory(const std::string& path);

}  // namespace torsion::device
