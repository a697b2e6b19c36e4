#pragma once
// Where the demo data (scenes, meshes, trajectories) lives, found from the running program rather
// than from a path compiled into it, so an installed `torsion` works wherever its prefix is copied:
//
//   <prefix>/bin/torsion                  the program
//   <prefix>/share/torsion/demos/scenes   the named scenes (they refer to ../../assets/...)
//   <prefix>/share/torsion/assets         meshes, trajectories, .bullet files
//
// The build tree has the same shape: CMake links <build>/share/torsion/demos/scenes and
// <build>/share/torsion/assets to the source tree's directories.

#include <optional>
#include <string>

namespace torsion::scene {

/// The first `share/torsion` directory found in the running program's directory or one of its
/// three nearest ancestors (a test binary lives deeper in the build tree than `torsion`); none
/// when the program's path cannot be read (no /proc) or no such directory exists.
std::optional<std::string> dataDirectory();

}  // namespace torsion::scene
