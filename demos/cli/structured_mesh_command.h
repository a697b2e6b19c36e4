#pragma once
// `torsion mesh box` and `torsion mesh ball`: structured tet meshes made without tetgen (the
// contact scenes' slabs, blocks and balls; assets/recipes/make_assets.sh).

#include <CLI/CLI.hpp>

#include "command_action.h"

namespace torsion::cli {

void addStructuredMeshCommands(CLI::App& mesh, CommandAction& chosen);

}  // namespace torsion::cli
