#pragma once
// `torsion mesh cylinder` and `torsion mesh tetrahedralize`: mesh generation by calling Debian's
// tetgen command (TetGen is AGPL: we run the program, never link it).

#include <CLI/CLI.hpp>

namespace torsion::cli {

void addMeshGenerateCommands(CLI::App& mesh);

}  // namespace torsion::cli
