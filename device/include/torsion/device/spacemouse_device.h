#pragma once
// A 3Dconnexion SpaceMouse through libspnav and the spacenavd daemon (Debian packages
// libspnav-dev, spacenavd). Its readings are integrated into a pose (spacemouse_integrator.h);
// buttons map as the report's section 5.4 (the first grabs and enables force, the second
// releases); it has no motors, so its force limits are zero and written wrenches are dropped.
// libspnav keeps one connection per process, so at most one SpaceMouse device is open at a
// time. When Torsion was built without libspnav, openSpaceMouse() says so.

#include <memory>

#include "torsion/device/haptic_device.h"
#include "torsion/device/loaded.h"
#include "torsion/device/spacemouse_integrator.h"

namespace torsion::device {

/// True when this build has libspnav.
bool spaceMouseSupported();

/// Connects to spacenavd. Errors: built without libspnav; no daemon answering; already open.
Loaded<std::unique_ptr<HapticDevice>> openSpaceMouse(const SpaceMouseSettings& settings);

}  // namespace torsion::device
