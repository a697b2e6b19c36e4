#pragma once
// A device moved by `torsion view`'s mouse and keys: the viewer sets its pose and buttons from
// the GUI thread, the haptic loop reads them from its own thread (threaded mode) or from the
// simulation thread (lockstep). It has no motors: written wrenches are kept so that the viewer
// can show what a real device would render. A mutex guards the shared state: the loop reads a
// whole (pose, buttons) pair, never half of one update and half of the next, and the sections
// are a few copies long, so a 1 kHz loop never waits on them for long.

#include <cstdint>
#include <mutex>

#include "torsion/device/haptic_device.h"

namespace torsion::device {

class ManualDevice : public HapticDevice {
 public:
  /// Starts at the zero pose (the tool's or hand's starting frame), no button held.
  explicit ManualDevice(DeviceLimits limits) : limits_(limits) {}

  std::string name() const override { return "manual"; }
  DeviceLimits limits() const override { return limits_; }
  /// The last pose and buttons set, at `time`; always alive (the viewer is its operator).
  DeviceSample read(double time) override;
  void write(const Wrench& wrench) override;

  /// Any thread: where the device is now (device frame).
  void setPose(const Pose& pose);
  /// Any thread: the buttons held now (bit k: button k+1).
  void setButtons(std::uint32_t buttons);
  /// Any thread: the pose and buttons the next read() returns.
  Pose pose() const;
  std::uint32_t buttons() const;
  /// Any thread: the wrench last written (device frame).
  Wrench lastWritten() const;

 private:
  const DeviceLimits limits_;
  mutable std::mutex mutex_;  // guards the three below
  Pose pose_;
  std::uint32_t buttons_ = 0;
  Wrench written_;
};

}  // namespace torsion::device
