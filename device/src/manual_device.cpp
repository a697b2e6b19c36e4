#include "torsion/device/manual_device.h"

#include <algorithm>

#include "torsion/device/pose_math.h"

namespace torsion::device {

DeviceSample ManualDevice::read(double time) {
  DeviceSample sample;
  sample.time = time;
  sample.alive = true;
  std::lock_guard<std::mutex> lock(mutex_);
  const double elapsed = have_read_ ? std::max(0.0, time - last_read_) : glide_left_;
  if (glide_left_ > 0 && elapsed < glide_left_) {
    // Even motion: the same fraction of what is left as of the time that is left.
    const double u = elapsed / glide_left_;
    pose_.position = pose_.position + u * (target_.position - pose_.position);
    pose_.orientation = slerp(pose_.orientation, target_.orientation, u);
    glide_left_ -= elapsed;
  } else {
    pose_ = target_;  // arrived (exactly: the glide ends on the pose set)
    glide_left_ = 0;
  }
  have_read_ = true;
  last_read_ = time;
  sample.pose = pose_;
  sample.buttons = buttons_;
  return sample;
}

void ManualDevice::write(const Wrench& wrench) {
  std::lock_guard<std::mutex> lock(mutex_);
  written_ = wrench;
}

void ManualDevice::setPose(const Pose& pose) {
  std::lock_guard<std::mutex> lock(mutex_);
  target_ = pose;
  glide_left_ = glide_time_;
}

void ManualDevice::setButtons(std::uint32_t buttons) {
  std::lock_guard<std::mutex> lock(mutex_);
  buttons_ = buttons;
}

Wrench ManualDevice::lastWritten() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

}  // namespace torsion::device
