#include "surface_mesh.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <utility>

#include "torsion/mesh/mesh_io.h"

namespace torsion::meshgen {

namespace fs = std::filesystem;

namespace {

std::string where(const std::string& file, const SurfaceMesh& surface, size_t triangle) {
  const int line = triangle < surface.triangle_lines.size() ? surface.triangle_lines[triangle] : 0;
  if (line > 0) return file + ":" + std::to_string(line) + ": ";
  return file + ": triangle " + std::to_string(triangle) + ": ";
}

std::string pointText(const Eigen::Vector3d& p) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%.6g, %.6g, %.6g)", p.x(), p.y(), p.z());
  return buffer;
}

}  // namespace

Result<SurfaceMesh> readSurface(const fs::path& path) {
  const std::string ext = lowerExtension(path);
  if (ext != ".off" && ext != ".obj" && ext != ".stl" && ext != ".ply") {
    return Error{path.string() + ": unknown surface format '" + ext +
                 "' (known: .off, .obj, .stl, .ply)"};
  }
  Result<std::string> text = readTextFile(path);
  if (!text) return text.error();
  if (ext == ".off") return parseOff(text.value(), path.string());
  if (ext == ".obj") return parseObj(text.value(), path.string());
  if (ext == ".ply") return parsePly(text.value(), path.string());
  return parseStl(text.value(), path.string());
}

Status prepareClosedSurface(SurfaceMesh& surface, const std::string& file) {
  if (surface.triangles.size() < 4) {
    return Error{file + ": a closed surface needs at least 4 triangles, found " +
                 std::to_string(surface.triangles.size())};
  }
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    const auto& tri = surface.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      return Error{where(file, surface, t) + "triangle with a repeated vertex (" +
                   std::to_string(tri[0]) + ", " + std::to_string(tri[1]) + ", " +
                   std::to_string(tri[2]) + ")"};
    }
  }

  // Every edge must be shared by exactly two triangles.
  std::map<std::pair<int, int>, std::pair<int, size_t>> edges;  // edge -> (uses, first triangle)
  for (size_t t = 0; t < surface.triangles.size(); ++t) {
    const auto& tri = surface.triangles[t];
    for (int k = 0; k < 3; ++k) {
      int a = tri[static_cast<size_t>(k)], b = tri[static_cast<size_t>((k + 1) % 3)];
      if (a > b) std::swap(a, b);
      auto [it, inserted] = edges.emplace(std::make_pair(a, b), std::make_pair(0, t));
      ++it->second.first;
    }
  }
  size_t open = 0, crowded = 0;
  const std::pair<const std::pair<int, int>, std::pair<int, size_t>>* example = nullptr;
  for (const auto& entry : edges) {
    if (entry.second.first == 2) continue;
    if (entry.second.first == 1)
      ++open;
    else
      ++crowded;
    if (example == nullptr) example = &entry;
  }
  if (example != nullptr) {
    const auto [a, b] = example->first;
    const auto [uses, t] = example->second;
    return Error{where(file, surface, t) + "the surface is not closed: " + std::to_string(open) +
                 " edge(s) used by one triangle, " + std::to_string(crowded) +
                 " by more than two; e.g. edge " +
                 pointText(surface.vertices[static_cast<size_t>(a)]) + " - " +
                 pointText(surface.vertices[static_cast<size_t>(b)]) + " is used by " +
                 std::to_string(uses) + " triangle(s)"};
  }

  // Drop vertices no triangle uses (tetgen would keep them as loose points).
  std::vector<int> remap(surface.vertices.size(), -1);
  for (const auto& tri : surface.triangles) {
    for (int v : tri)
      remap[static_cast<size_t>(v)] = 0;
  }
  std::vector<Eigen::Vector3d> kept;
  for (size_t v = 0; v < remap.size(); ++v) {
    if (remap[v] < 0) continue;
    remap[v] = static_cast<int>(kept.size());
    kept.push_back(surface.vertices[v]);
  }
  for (auto& tri : surface.triangles) {
    for (int& v : tri)
      v = remap[static_cast<size_t>(v)];
  }
  surface.vertices = std::move(kept);
  return Ok{};
}

std::string formatSmesh(const SurfaceMesh& surface, std::string_view comment) {
  std::string text = "# " + std::string(comment) + "\n";
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "%zu 3 0 0\n", surface.vertices.size());
  text += buffer;
  for (size_t v = 0; v < surface.vertices.size(); ++v) {
    const Eigen::Vector3d& p = surface.vertices[v];
    std::snprintf(buffer, sizeof buffer, "%zu %.17g %.17g %.17g\n", v, p.x(), p.y(), p.z());
    text += buffer;
  }
  std::snprintf(buffer, sizeof buffer, "%zu 0\n", surface.triangles.size());
  text += buffer;
  for (const auto& tri : surface.triangles) {
    std::snprintf(buffer, sizeof buffer, "3 %d %d %d\n", tri[0], tri[1], tri[2]);
    text += buffer;
  }
  text += "0\n0\n";  // no holes, no regions
  return text;
}

}  // namespace torsion::meshgen
