#include "torsion/device/manual_device.h"

namespace torsion::device {

DeviceSample ManualDevice::read(double time) {
  DeviceSample sample;
  sample.time = time;
  sample.alive = true;
  std::lock_guard<std::mutex> lock(mutex_);
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
  pose_ = pose;
}

void ManualDevice::setButtons(std::uint32_t buttons) {
  std::lock_guard<std::mutex> lock(mutex_);
  buttons_ = buttons;
}

Pose ManualDevice::pose() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pose_;
}

std::uint32_t ManualDevice::buttons() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return buttons_;
}

Wrench ManualDevice::lastWritten() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

}  // namespace torsion::device
