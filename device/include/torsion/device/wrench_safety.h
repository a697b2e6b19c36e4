#pragma once
// Pure functions that keep a wrench safe for the hand. Every wrench goes through them before a
// device sees it.

#include "torsion/device/device_types.h"

namespace torsion::device {

/// True when all six components are finite.
bool isFinite(const Wrench& wrench);

/// Scales force and torque (each as a vector, so direction is kept) down to the device's limits.
/// A wrench with any non-finite component becomes zero: NaN never reaches a device.
Wrench saturate(const Wrench& wrench, const DeviceLimits& limits);

}  // namespace torsion::device
