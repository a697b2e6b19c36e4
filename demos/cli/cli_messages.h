#pragma once
// The tool's two kinds of message on stderr, worded alike by every subcommand: "error: ..."
// (the subcommand then exits 1) and "warning: ..." for what a mesh reader noticed.

#include <iostream>
#include <string>

#include "torsion/mesh/tet_mesh_builder.h"

namespace torsion::cli {

/// Prints "error: message" and returns the exit code of bad input or a failed write (1).
inline int fail(const std::string& message) {
  std::cerr << "error: " << message << "\n";
  return 1;
}

/// Prints each of the reader's warnings about a loaded mesh.
inline void printWarnings(const LoadedMesh& loaded) {
  for (const std::string& w : loaded.warnings)
    std::cerr << "warning: " << w << "\n";
}

}  // namespace torsion::cli
