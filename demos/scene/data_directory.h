#pragma once
// Where the demo data (scenes, meshes, trajectories) lives, found from the running program rather
// than from a path compiled into it, so an installed `torsion` works wherever its prefix is copied:
//
//   <prefix>/bin/torsion                  the program
//   <prefix>/share/torsion/demos/scenes   the named scenes (they refer to ../../assets/...)
//   <prefix>/share/torsion/assets         meshes, trajectories, .bullet files
//
// The build tree has the same shape: CMake links <build>/share/torsion/demos/scenes and
// <build>/share/torsion/assets to the source tree's directories. A wheel of the Python package
// (`pip install .`) holds the same two folders inside the package, beside the module:
//
//   <site-packages>/torsion/_torsion.*.so
//   <site-packages>/torsion/data/demos/scenes, <site-packages>/torsion/data/assets

#include <optional>
#include <string>

namespace torsion::scene {

/// The `data` directory beside the file this code was loaded from (a wheel's package), else the
/// first `share/torsion` directory found beside, or up to a few levels above, that file (a shared
/// object such as the Python module, then the running program; a test binary lives deeper in the
/// build tree than `torsion`); none when no such directory exists. Either holds demos/scenes.
std::optional<std::string> dataDirectory();

}  // namespace torsion::scene
