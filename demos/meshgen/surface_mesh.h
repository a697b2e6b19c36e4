#pragma once
// Closed triangle surfaces, the input of `torsion mesh tetrahedralize`: readers for .off, .obj
// and .stl (ASCII and binary), a closedness check, and the TetGen .smesh text handed to tetgen.

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "torsion/result.h"

namespace torsion::meshgen {

struct SurfaceMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;  ///< 0-based vertex indices
  std::vector<int> triangle_lines;            ///< 1-based source line of each triangle (0: none)
};

/// Object File Format: "OFF" header (optionally with the counts on the same line), then
/// "<#vertices> <#faces> <#edges>", vertex lines "x y z [...]" and face lines "n i0 .. in-1 [...]"
/// (0-based). Polygons are fan-triangulated; extra numbers (colours) are ignored; '#' comments.
Result<SurfaceMesh> parseOff(std::string_view text, const std::string& file);

/// Wavefront OBJ: "v x y z [w]" and "f a b c ..." lines (indices 1-based, negative ones relative to
/// the vertices read so far; "a/t/n", "a//n" and "a/t" forms). Polygons are fan-triangulated;
/// vt, vn, g, o, s, usemtl, mtllib and other statements are ignored; '#' comments.
Result<SurfaceMesh> parseObj(std::string_view text, const std::string& file);

/// STL, ASCII ("solid ... facet normal ... outer loop vertex x y z ... endloop endfacet ...
/// endsolid") or binary (80-byte header, uint32 count, 50 bytes per triangle). STL repeats every
/// vertex in each triangle: vertices with identical coordinates are merged.
Result<SurfaceMesh> parseStl(std::string_view bytes, const std::string& file);

/// Stanford PLY, ASCII or binary (either endianness): the "vertex" element's x, y, z (any numeric
/// type) and the "face" element's vertex_indices (or vertex_index) lists, fan-triangulated; other
/// elements and properties are skipped. Errors name the file and the element.
Result<SurfaceMesh> parsePly(std::string_view bytes, const std::string& file);

/// Reads a surface by the file's extension (.off, .obj, .stl, .ply; case-insensitive).
Result<SurfaceMesh> readSurface(const std::filesystem::path& path);

/// Makes the surface ready for tetgen and checks it is closed: refuses triangles with a repeated
/// vertex (naming file:line), drops vertices no triangle uses, and refuses edges that are not
/// shared by exactly two triangles (open boundaries, naming one such edge and its line).
Status prepareClosedSurface(SurfaceMesh& surface, const std::string& file);

/// TetGen .smesh text: the points (0-based, round-trip precision) and one facet per triangle.
std::string formatSmesh(const SurfaceMesh& surface, std::string_view comment);

}  // namespace torsion::meshgen
