#pragma once
// DeviceSpec -> an open device: loads the trajectory or log, binds the UDP port, connects to
// spacenavd. Errors say what failed (the file and key, the port, the missing daemon).

#include <memory>

#include "device_spec.h"
#include "torsion/device/haptic_device.h"
#include "torsion/result.h"

namespace torsion::scene {

Result<std::unique_ptr<device::HapticDevice>> openDevice(const DeviceSpec& spec);

}  // namespace torsion::scene
