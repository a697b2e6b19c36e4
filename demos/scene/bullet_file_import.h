#pragma once
// A scene's "bullet_file": the rigid bodies of a file Bullet's serializer wrote, read by Bullet's
// own btBulletWorldImporter in a child process of its own (isolated_call.h), because that reader
// is not memory-safe on a malformed file. Only a description of the bodies comes back, in the
// scene file's own rigid_bodies form, and the scene parser reads it with the same checks as a
// scene file's rigid_bodies (names, shapes, masses, poses): a malformed or hostile .bullet file
// ends as an error naming it, never as a crash, a hang or garbage in the world.

#include <nlohmann/json.hpp>
#include <string>

#include "torsion/result.h"

namespace torsion::scene {

/// The rigid bodies of the .bullet file at `path` as {"rigid_bodies": [...]}
/// (bullet_file_reader.h). Errors: the file is missing or not a regular file, Bullet's reader
/// refuses it, crashes on it, hangs (20 s) or needs more than 2 GiB for it, and those of
/// bulletFileBodiesJson.
Result<nlohmann::json> importBulletFile(const std::string& path);

}  // namespace torsion::scene
