#pragma once
// Mesh files by name: the format follows the extension.
//   .node / .ele (or a base name with both beside it)  TetGen
//   .msh                                                Gmsh 2.2 / 4.1 ASCII
//   .vtk                                                legacy VTK unstructured grid

#include <filesystem>
#include <string>
#include <vector>

#include "torsion/mesh/mesh_fields.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/result.h"

namespace torsion {

enum class MeshFormat { kTetGen, kGmsh, kVtk };

/// The path's extension, lower-cased, with its dot (".msh"); empty when there is none.
std::string lowerExtension(const std::filesystem::path& path);

/// The format a path names by its extension, or an Error listing the known extensions.
Result<MeshFormat> meshFormatOf(const std::filesystem::path& path);

/// Reads, parses and validates. Errors name the file (and line or element) and the fault:
/// missing or unreadable file, empty file, syntax, geometry.
Result<LoadedMesh> readMesh(const std::filesystem::path& path, const MeshLoadOptions& options = {});

/// Writes the mesh in the format of the path's extension (for TetGen, both .node and .ele beside
/// each other, replaced together or not at all). Fields are written only to VTK; other formats
/// ignore them.
Status writeMesh(const std::filesystem::path& path, const TetMesh& mesh,
                 const MeshFields& fields = {});

/// Whole file as text, or an Error: "<path>: cannot open: <reason>" / "<path>: file is empty".
/// Only regular files are read, up to device::maxInputFileBytes() (torsion/device/file_io.h).
Result<std::string> readTextFile(const std::filesystem::path& path);
/// Replaces the file by the text or leaves it as it was (temporary beside it, flushed, renamed),
/// or an Error naming the path and the reason.
Status writeTextFile(const std::filesystem::path& path, const std::string& text);

}  // namespace torsion
