#include "torsion/device/trajectory.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "torsion/device/pose_math.h"

namespace torsion::device {

Trajectory::Trajectory(std::vector<TrajectoryKeyframe> keyframes, std::vector<ButtonEvent> buttons)
    : keyframes_(std::move(keyframes)), buttons_(std::move(buttons)) {}

Pose Trajectory::poseAt(double time) const {
  if (keyframes_.empty()) return Pose{};
  if (!(time > keyframes_.front().time)) return keyframes_.front().pose;
  if (time >= keyframes_.back().time) return keyframes_.back().pose;
  const auto after =
      std::upper_bound(keyframes_.begin(), keyframes_.end(), time,
                       [](double t, const TrajectoryKeyframe& k) { return t < k.time; });
  const TrajectoryKeyframe& b = *after;
  const TrajectoryKeyframe& a = *(after - 1);
  const double u = (time - a.time) / (b.time - a.time);
  Pose p;
  p.position = a.pose.position + u * (b.pose.position - a.pose.position);
  p.orientation = slerp(a.pose.orientation, b.pose.orientation, u);
  return p;
}

std::uint32_t Trajectory::buttonsAt(double time) const {
  std::uint32_t held = 0;
  for (const ButtonEvent& e : buttons_) {
    if (e.time > time) break;
    held = e.held;
  }
  return held;
}

Trajectory Trajectory::playedAt(double speed) const {
  Trajectory faster = *this;
  for (TrajectoryKeyframe& k : faster.keyframes_)
    k.time /= speed;
  for (ButtonEvent& b : faster.buttons_)
    b.time /= speed;
  return faster;
}

double Trajectory::duration() const {
  double end = keyframes_.empty() ? 0.0 : keyframes_.back().time;
  if (!buttons_.empty()) end = std::max(end, buttons_.back().time);
  return end;
}

std::vector<TrajectoryKeyframe> keyframesFromSegments(const Pose& start,
                                                      const std::vector<MotionSegment>& segments) {
  constexpr double kMaxTurnPerKeyframe = 0.5;  // rad, well below pi so slerp is exact
  std::vector<TrajectoryKeyframe> keyframes{{0.0, start}};
  for (const MotionSegment& s : segments) {
    const double turn = norm(s.angular_velocity) * s.duration;
    const int pieces = std::max(1, static_cast<int>(std::ceil(turn / kMaxTurnPerKeyframe)));
    const double dt = s.duration / pieces;
    for (int k = 0; k < pieces; ++k) {
      const TrajectoryKeyframe& last = keyframes.back();
      TrajectoryKeyframe next;
      next.time = last.time + dt;
      next.pose.position = last.pose.position + dt * s.linear_velocity;
      next.pose.orientation =
          normalized(fromRotationVector(dt * s.angular_velocity) * last.pose.orientation);
      keyframes.push_back(next);
    }
  }
  return keyframes;
}

}  // namespace torsion::device
