// Object File Format surfaces (.off).

#include <string>

#include "surface_mesh.h"
#include "surface_text.h"

namespace torsion::meshgen {

namespace {

using detail::LineCursor;
using detail::quoted;

SurfaceMesh parseOffOrThrow(std::string_view text, const std::string& file) {
  LineCursor in(text, file, '#');
  in.require("the 'OFF' header");
  const std::string_view keyword = in.tokens()[0];
  if (keyword.size() < 3 || keyword.substr(keyword.size() - 3) != "OFF") {
    in.fail("expected the 'OFF' header, got " + quoted(keyword));
  }
  if (keyword != "OFF") {
    in.fail("only plain 'OFF' files are read (no colour, normal or texture variants), got " +
            quoted(keyword));
  }
  // The counts may follow the keyword on the same line.
  std::vector<std::string_view> counts(in.tokens().begin() + 1, in.tokens().end());
  if (counts.empty()) {
    in.require("the counts line '<#vertices> <#faces> <#edges>'");
    counts = in.tokens();
  }
  if (counts.size() < 2) in.fail("expected '<#vertices> <#faces> <#edges>'");
  const long vertex_count = in.integer(counts[0], "the vertex count");
  const long face_count = in.integer(counts[1], "the face count");
  if (vertex_count < 3)
    in.fail("needs at least 3 vertices, the header says " + std::string(counts[0]));
  if (face_count < 1) in.fail("needs at least 1 face, the header says " + std::string(counts[1]));
  if (vertex_count > 100'000'000 || face_count > 100'000'000) {
    in.fail("implausibly large counts in the header");
  }

  SurfaceMesh surface;
  surface.vertices.reserve(static_cast<size_t>(vertex_count));
  for (long v = 0; v < vertex_count; ++v) {
    in.require("vertex " + std::to_string(v) + " of " + std::to_string(vertex_count));
    const auto& t = in.tokens();
    if (t.size() < 3) {
      in.fail("vertex " + std::to_string(v) + ": expected 3 coordinates, got " +
              std::to_string(t.size()));
    }
    surface.vertices.emplace_back(in.real(t[0], "x"), in.real(t[1], "y"), in.real(t[2], "z"));
  }
  for (long f = 0; f < face_count; ++f) {
    in.require("face " + std::to_string(f) + " of " + std::to_string(face_count));
    const auto& t = in.tokens();
    const std::string face = "face " + std::to_string(f);
    const long n = in.integer(t[0], "the corner count of " + face);
    if (n < 3) in.fail(face + ": a face needs at least 3 corners, got " + std::to_string(n));
    if (t.size() < static_cast<size_t>(n) + 1) {
      in.fail(face + ": expected " + std::to_string(n) + " vertex indices, got " +
              std::to_string(t.size() - 1));
    }
    std::vector<int> corners;
    for (long k = 1; k <= n; ++k) {
      const long index = in.integer(t[static_cast<size_t>(k)], "a vertex index of " + face);
      if (index < 0 || index >= vertex_count) {
        in.fail(face + ": vertex index " + std::to_string(index) + " out of range (" +
                std::to_string(vertex_count) + " vertices, 0-based)");
      }
      corners.push_back(static_cast<int>(index));
    }
    for (size_t k = 1; k + 1 < corners.size(); ++k) {
      surface.triangles.push_back({corners[0], corners[k], corners[k + 1]});
      surface.triangle_lines.push_back(in.line());
    }
  }
  return surface;
}

}  // namespace

Result<SurfaceMesh> parseOff(std::string_view text, const std::string& file) {
  try {
    return parseOffOrThrow(text, file);
  } catch (const detail::SurfaceParseError& e) {
    return Error{e.what()};
  }
}

}  // namespace torsion::meshgen
