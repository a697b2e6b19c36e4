#pragma once
// The named demo scenes: `torsion run drop` finds demos/scenes/drop.json. A scene argument that
// names an existing file is used as it is; a bare name (no directory, no extension) is looked up
// in the scene directories: $TORSION_SCENE_PATH (colon-separated) first, then the demo scenes of
// the installation or build tree the program runs from (data_directory.h; the scenes refer to
// the assets by relative paths, so they run from either).

#include <string>
#include <vector>

#include "torsion/result.h"

namespace torsion::scene {

/// The directories searched for named scenes, in order.
std::vector<std::string> sceneDirectories();

/// Every scene name found in those directories (file stems of *.json), sorted, without repeats.
std::vector<std::string> sceneNames();

/// `argument` if it names a file; else the first `<dir>/<argument>.json`; else an error naming
/// the argument, the directories searched and the scenes available.
Result<std::string> resolveScene(const std::string& argument);

}  // namespace torsion::scene
