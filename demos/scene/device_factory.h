#pragma once
// DeviceSpec -> an open device: loads the trajectory or log, binds the UDP port, connects to
// spacenavd, loads a device plug-in. Errors say what failed (the file and key, the port, the
// missing daemon).

#include <memory>

#include "device_spec.h"
#include "torsion/device/haptic_device.h"
#include "torsion/result.h"

namespace torsion::scene {

/// `lockstep`: the haptic loop ticks on the simulated clock (a plug-in's reads are then given
/// a long wall-clock deadline, so that a run is the same whatever the machine's load).
Result<std::unique_ptr<device::HapticDevice>> openDevice(const DeviceSpec& spec,
                                                         bool lockstep = false);

}  // namespace torsion::scene
