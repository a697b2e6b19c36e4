// openSpaceMouse() in a build without libspnav (see spacemouse_device.cpp for the real one).
#include "torsion/device/spacemouse_device.h"

namespace torsion::device {

bool spaceMouseSupported() {
  return false;
}

Loaded<std::unique_ptr<HapticDevice>> openSpaceMouse(const SpaceMouseSettings&) {
  return Loaded<std::unique_ptr<HapticDevice>>::fail(
      "SpaceMouse: this build of Torsion has no libspnav (install the Debian package "
      "libspnav-dev, or run scripts/setup.sh, and rebuild)");
}

}  // namespace torsion::device
