#pragma once
// Running Debian's `gmsh` program (GPL: we run it and read the .msh it writes, we never link it)
// to fill a closed surface with tets: the surface goes in as STL, Gmsh remeshes it (its surfaces
// classified at 40 degrees, so sharp edges stay) and fills the volume with tets no longer than a
// given edge length.

#include <filesystem>
#include <string>
#include <string_view>

#include "surface_mesh.h"
#include "torsion/result.h"

namespace torsion::meshgen {

/// The gmsh program, or the error "torsion mesh <command>: needs the 'gmsh' command (Debian
/// package 'gmsh'); it is not on PATH".
Result<std::filesystem::path> findGmsh(std::string_view command);

/// Meshes `surface` in `dir` (a scratch directory); returns the path of the .msh (format 2.2)
/// Gmsh wrote. `max_edge` (m): the longest tet edge Gmsh aims for; 0: Gmsh's own default.
Result<std::filesystem::path> runGmsh(const std::filesystem::path& gmsh, const SurfaceMesh& surface,
                                      double max_edge, const std::filesystem::path& dir);

}  // namespace torsion::meshgen
