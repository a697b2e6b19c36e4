// STL surfaces (.stl), ASCII and binary. Vertices with identical coordinates are merged.

#include <cstdint>
#include <cstring>
#include <map>
#include <string>

#include "surface_mesh.h"
#include "surface_text.h"

namespace torsion::meshgen {

namespace {

using detail::LineCursor;
using detail::quoted;

class VertexMerger {
 public:
  explicit VertexMerger(SurfaceMesh& surface) : surface_(surface) {}
  int add(const Eigen::Vector3d& p) {
    const std::array<double, 3> key{p.x(), p.y(), p.z()};
    const auto [it, inserted] = index_.emplace(key, static_cast<int>(surface_.vertices.size()));
    if (inserted) surface_.vertices.push_back(p);
    return it->second;
  }

 private:
  SurfaceMesh& surface_;
  std::map<std::array<double, 3>, int> index_;
};

bool startsWithSolid(std::string_view bytes) {
  size_t i = 0;
  while (i < bytes.size() &&
         (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\r' || bytes[i] == '\n')) {
    ++i;
  }
  return bytes.substr(i, 5) == "solid";
}

std::uint32_t readU32(std::string_view bytes, size_t offset) {
  unsigned char b[4];
  std::memcpy(b, bytes.data() + offset, 4);
  return static_cast<std::uint32_t>(b[0]) | (static_cast<std::uint32_t>(b[1]) << 8) |
         (static_cast<std::uint32_t>(b[2]) << 16) | (static_cast<std::uint32_t>(b[3]) << 24);
}

float readF32(std::string_view bytes, size_t offset) {
  const std::uint32_t bits = readU32(bytes, offset);
  float value = 0;
  static_assert(sizeof value == sizeof bits);
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

Result<SurfaceMesh> parseBinaryStl(std::string_view bytes, const std::string& file) {
  const std::uint32_t count = readU32(bytes, 80);
  SurfaceMesh surface;
  VertexMerger merger(surface);
  for (std::uint32_t t = 0; t < count; ++t) {
    const size_t base = 84 + 50 * static_cast<size_t>(t);
    std::array<int, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      Eigen::Vector3d p;
      for (int k = 0; k < 3; ++k) {
        const float v =
            readF32(bytes, base + 12 + 12 * static_cast<size_t>(c) + 4 * static_cast<size_t>(k));
        if (!std::isfinite(v)) {
          return Error{file + ": binary STL triangle " + std::to_string(t) + " (byte " +
                       std::to_string(base) + "): non-finite coordinate"};
        }
        p[k] = static_cast<double>(v);
      }
      tri[static_cast<size_t>(c)] = merger.add(p);
    }
    surface.triangles.push_back(tri);
    surface.triangle_lines.push_back(0);
  }
  if (surface.triangles.empty()) return Error{file + ": binary STL with no triangles"};
  return surface;
}

void expectWords(LineCursor& in, std::initializer_list<std::string_view> words,
                 const std::string& what) {
  in.require(what);
  const auto& t = in.tokens();
  size_t k = 0;
  for (std::string_view w : words) {
    if (k >= t.size() || t[k] != w) in.fail("expected " + what + ", got " + quoted(t[0]));
    ++k;
  }
}

SurfaceMesh parseAsciiStlOrThrow(std::string_view text, const std::string& file) {
  LineCursor in(text, file, '\0');
  SurfaceMesh surface;
  VertexMerger merger(surface);
  in.require("'solid'");
  if (in.tokens()[0] != "solid") in.fail("expected 'solid', got " + quoted(in.tokens()[0]));
  bool in_solid = true;
  while (in.next()) {
    const auto& t = in.tokens();
    if (!in_solid) {
      if (t[0] != "solid") in.fail("expected 'solid' or the end of the file, got " + quoted(t[0]));
      in_solid = true;
      continue;
    }
    if (t[0] == "endsolid") {
      in_solid = false;
      continue;
    }
    if (t[0] != "facet") in.fail("expected 'facet' or 'endsolid', got " + quoted(t[0]));
    const int facet_line = in.line();
    expectWords(in, {"outer", "loop"}, "'outer loop'");
    std::array<int, 3> tri{};
    for (size_t c = 0; c < 3; ++c) {
      in.require("'vertex x y z'");
      const auto& v = in.tokens();
      if (v[0] != "vertex") in.fail("expected 'vertex x y z', got " + quoted(v[0]));
      if (v.size() < 4) {
        in.fail("vertex: expected 3 coordinates, got " + std::to_string(v.size() - 1));
      }
      tri[c] =
          merger.add(Eigen::Vector3d(in.real(v[1], "x"), in.real(v[2], "y"), in.real(v[3], "z")));
    }
    expectWords(in, {"endloop"}, "'endloop' (STL facets are triangles)");
    expectWords(in, {"endfacet"}, "'endfacet'");
    surface.triangles.push_back(tri);
    surface.triangle_lines.push_back(facet_line);
  }
  if (in_solid) in.failAt(in.line(), "unexpected end of file, expected 'endsolid'");
  if (surface.triangles.empty()) in.failAt(in.line(), "no facets");
  return surface;
}

}  // namespace

Result<SurfaceMesh> parseStl(std::string_view bytes, const std::string& file) {
  // Binary files may begin with "solid" too, so the size test comes first.
  if (bytes.size() >= 84) {
    const std::uint64_t count = readU32(bytes, 80);
    if (84 + 50 * count == bytes.size()) return parseBinaryStl(bytes, file);
  }
  if (startsWithSolid(bytes)) {
    try {
      return parseAsciiStlOrThrow(bytes, file);
    } catch (const detail::SurfaceParseError& e) {
      return Error{e.what()};
    }
  }
  if (bytes.size() < 84) {
    return Error{file + ": not an STL file: too short for binary STL (" +
                 std::to_string(bytes.size()) + " bytes) and no 'solid' keyword"};
  }
  const std::uint64_t count = readU32(bytes, 80);
  return Error{file + ": binary STL header declares " + std::to_string(count) + " triangles (" +
               std::to_string(84 + 50 * count) + " bytes) but the file has " +
               std::to_string(bytes.size()) + " bytes"};
}

}  // namespace torsion::meshgen
