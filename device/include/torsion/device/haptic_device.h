#pragma once
// The one interface every device implements (scripted, replay, SpaceMouse, network). Called only
// from the haptic loop's thread.

#include <string>

#include "torsion/device/device_types.h"

namespace torsion::device {

class HapticDevice {
 public:
  virtual ~HapticDevice() = default;

  /// Human-readable name for logs and errors, e.g. "scripted(figure_6_7.json)".
  virtual std::string name() const = 0;
  /// Physical limits; output is saturated to these.
  virtual DeviceLimits limits() const = 0;
  /// Reads pose and buttons; `time` is the loop's clock in seconds.
  virtual DeviceSample read(double time) = 0;
  /// Sends the wrench to render. Devices without force output ignore it.
  virtual void write(const Wrench& wrench) = 0;
};

}  // namespace torsion::device
