#pragma once
// A device moved by `torsion view`'s mouse and keys: the viewer sets its pose and buttons from
// the GUI thread, the haptic loop reads them from its own thread (threaded mode) or from the
// simulation thread (lockstep). It has no motors: written wrenches are kept so that the viewer
// can show what a real device would render. A mutex guards the shared state: the loop reads a
// whole (pose, buttons) pair, never half of one update and half of the next, and the sections
// are a few copies long, so a 1 kHz loop never waits on them for long.
//
// A key press or a drag moves the pose in one jump; a hand on a device does not. The device
// therefore glides to each pose it is given, evenly over `glide_time` of the loop's clock
// (position along the line, orientation along the shorter arc). A jump would read as a burst of
// speed: the loop's reading check refuses one beyond a hand's speed, and the passivity
// controller, which bounds the coming motion by the last ticks' peak speed, would hold the
// rendered wrench near zero while the hand then rests (nothing moves to damp the debt away).

#include <cstdint>
#include <mutex>

#include "torsion/device/haptic_device.h"

namespace torsion::device {

class ManualDevice : public HapticDevice {
 public:
  /// s a hand takes to follow a key press (about the quickest deliberate reach).
  static constexpr double kDefaultGlideTime = 0.1;

  /// Starts at the zero pose (the tool's or hand's starting frame), no button held. A
  /// `glide_time` of 0 jumps to each pose at the next read.
  explicit ManualDevice(DeviceLimits limits, double glide_time = kDefaultGlideTime)
      : limits_(limits), glide_time_(glide_time) {}

  std::string name() const override { return "manual"; }
  DeviceLimits limits() const override { return limits_; }
  /// Where the glide toward the last pose set has got at `time` (the loop's clock), and the
  /// buttons set; always alive (the viewer is its operator). The first read is at that pose.
  DeviceSample read(double time) override;
  void write(const Wrench& wrench) override;

  /// Any thread: where the device is to go (device frame); it glides there from where it is.
  void setPose(const Pose& pose);
  /// Any thread: the buttons held now (bit k: button k+1).
  void setButtons(std::uint32_t buttons);
  /// Any thread: the wrench last written (device frame).
  Wrench lastWritten() const;

 private:
  const DeviceLimits limits_;
  const double glide_time_;
  mutable std::mutex mutex_;  // guards everything below
  Pose target_;
  Pose pose_;               // where the last read() left the device
  double glide_left_ = 0;   // s of the glide toward target_ still to go
  double last_read_ = 0;    // s, the loop's clock at the last read()
  bool have_read_ = false;  // no read yet: the first is at target_
  std::uint32_t buttons_ = 0;
  Wrench written_;
};

}  // namespace torsion::device
