#pragma once
// What a picture of a PyWorld shows (World.render, the passive viewer): the scene's frame data
// plus the hands Python added in code, which the scene does not list.

#include "frame_data.h"
#include "py_world.h"

namespace torsion::python {

/// The world as it is now; the caller holds a WorldGuard.
render::FrameData captureWorldFrame(PyWorld& world);

}  // namespace torsion::python
