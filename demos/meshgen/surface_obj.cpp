// Wavefront OBJ surfaces (.obj): vertices and faces only.

#include <string>

#include "surface_mesh.h"
#include "surface_text.h"

namespace torsion::meshgen {

namespace {

using detail::LineCursor;
using detail::quoted;

// "7", "7/2", "7/2/5", "7//5", "-1/-1/-1": the vertex index is the part before the first '/'.
int vertexIndex(const LineCursor& in, std::string_view token, size_t vertex_count) {
  const std::string_view head = token.substr(0, token.find('/'));
  if (head.empty()) in.fail("face corner " + quoted(token) + " has no vertex index");
  const long index = in.integer(head, "a face's vertex index");
  const long count = static_cast<long>(vertex_count);
  long resolved = 0;
  if (index > 0) {
    resolved = index - 1;
  } else if (index < 0) {
    resolved = count + index;  // -1 is the last vertex read so far
  } else {
    in.fail("face corner " + quoted(token) + ": vertex index 0 is invalid (OBJ counts from 1)");
  }
  if (resolved < 0 || resolved >= count) {
    in.fail("face corner " + quoted(token) + ": vertex index " + std::to_string(index) +
            " out of range (" + std::to_string(count) + " vertices read so far)");
  }
  return static_cast<int>(resolved);
}

SurfaceMesh parseObjOrThrow(std::string_view text, const std::string& file) {
  LineCursor in(text, file, '#');
  SurfaceMesh surface;
  while (in.next()) {
    const auto& t = in.tokens();
    if (t[0] == "v") {
      if (t.size() < 4) {
        in.fail("vertex: expected 3 coordinates after 'v', got " + std::to_string(t.size() - 1));
      }
      surface.vertices.emplace_back(in.real(t[1], "x"), in.real(t[2], "y"), in.real(t[3], "z"));
    } else if (t[0] == "f") {
      if (t.size() < 4) {
        in.fail("face: needs at least 3 corners, got " + std::to_string(t.size() - 1));
      }
      std::vector<int> corners;
      for (size_t k = 1; k < t.size(); ++k) {
        corners.push_back(vertexIndex(in, t[k], surface.vertices.size()));
      }
      for (size_t k = 1; k + 1 < corners.size(); ++k) {
        surface.triangles.push_back({corners[0], corners[k], corners[k + 1]});
        surface.triangle_lines.push_back(in.line());
      }
    }
    // vt, vn, vp, g, o, s, l, p, usemtl, mtllib, ...: not geometry we need.
  }
  if (surface.vertices.empty()) in.failAt(in.line() > 0 ? in.line() : 1, "no 'v' lines");
  if (surface.triangles.empty()) in.failAt(in.line() > 0 ? in.line() : 1, "no 'f' lines");
  return surface;
}

}  // namespace

Result<SurfaceMesh> parseObj(std::string_view text, const std::string& file) {
  try {
    return parseObjOrThrow(text, file);
  } catch (const detail::SurfaceParseError& e) {
    return Error{e.what()};
  }
}

}  // namespace torsion::meshgen
