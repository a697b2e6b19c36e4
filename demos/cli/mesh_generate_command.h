#pragma once
// `torsion mesh cylinder` and `torsion mesh tetrahedralize`: mesh generation by calling Debian's
// tetgen command (TetGen is AGPL: we run the program, never link it).

#include <CLI/CLI.hpp>

#include "command_action.h"

namespace torsion::cli {

void addMeshGenerateCommands(CLI::App& mesh, CommandAction& chosen);

}  // namespace torsion::cli
