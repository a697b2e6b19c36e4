#pragma once
// A .bullet file's rigid bodies as a scene file's `rigid_bodies` (docs/scene-format.md): the JSON
// text {"rigid_bodies": [...]} with each body's name, shape, mass, pose, velocities, friction and
// restitution, read by Bullet's own btBulletWorldImporter.
//
// Bullet's reader is not memory-safe on a malformed file (a wrong block size, DNA or header
// byte reads and writes out of bounds): call this only inside runIsolated (isolated_call.h), as
// readBulletFileBodies does. What it returns is read back through the scene parser's own checks,
// so nothing from the file reaches the world unchecked.

#include <string>

#include "torsion/result.h"

namespace torsion::scene {

/// The rigid bodies of the .bullet file at `path`, as JSON text. Bodies are named by their names
/// in the file, else "<file stem>_<index>" (file order). Errors: not a .bullet file, no rigid
/// body, constraints (not imported), a shape a scene cannot describe, a pose whose rotation is
/// not a rotation (the file's data do not match its header's precision or pointer size), a
/// value that is not finite.
Result<std::string> bulletFileBodiesJson(const std::string& path);

}  // namespace torsion::scene
