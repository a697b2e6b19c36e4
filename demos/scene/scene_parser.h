#pragma once
// JSON scene files -> SceneSpec. Every fault is an Error naming the file and the key path
// ("twist.json: bodies[0].material.density: expected a number, found a string"), or the line and
// column for JSON syntax. Unknown keys are errors too, listing the keys that are allowed there.

#include <string>
#include <string_view>

#include "scene_spec.h"
#include "torsion/result.h"

namespace torsion::scene {

/// Parses scene text; relative mesh paths resolve against `base_directory`.
Result<SceneSpec> parseScene(std::string_view text, const std::string& file_name,
                             const std::string& base_directory);

/// Reads and parses a scene file, or a named demo scene (scene_catalog.h: `drop` finds
/// demos/scenes/drop.json).
Result<SceneSpec> loadScene(const std::string& path_or_name);

}  // namespace torsion::scene
