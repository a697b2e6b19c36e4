#include "torsion/mesh/tet_mesh_builder.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "tet_faces.h"

namespace torsion {

namespace {

std::string where(const RawTetMesh& raw, size_t t) {
  const ElementOrigin& o = raw.origins[t];
  std::ostringstream s;
  s << raw.element_file;
  if (o.line > 0) s << ":" << o.line;
  s << ": tet " << o.id;
  return s.str();
}

double longestEdge(const std::array<Eigen::Vector3d, 4>& x) {
  double longest = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      longest = std::max(longest, (x[static_cast<size_t>(i)] - x[static_cast<size_t>(j)]).norm());
    }
  }
  return longest;
}

// Readers without element ids or lines (structured meshes, tests) get the tet's index as its id.
void numberUnlabelledTets(RawTetMesh& raw) {
  if (raw.origins.size() == raw.tets.size()) return;
  raw.origins.resize(raw.tets.size());
  for (size_t t = 0; t < raw.tets.size(); ++t)
    raw.origins[t].id = static_cast<long>(t);
}

Status checkNodes(const RawTetMesh& raw) {
  const std::string& file = raw.element_file;
  if (raw.positions.empty()) return Error{file + ": the mesh has no nodes"};
  if (raw.tets.empty()) return Error{file + ": the mesh has no tetrahedra"};
  for (size_t n = 0; n < raw.positions.size(); ++n) {
    if (!raw.positions[n].allFinite()) {
      return Error{file + ": node " + std::to_string(n) + " has a non-finite coordinate"};
    }
  }
  return Ok{};
}

// Per tet: indices in range and distinct, a volume that is finite and not flat; an inverted tet
// is refused or reoriented (two vertices swapped), with one warning for all of them.
Status checkAndOrientTets(RawTetMesh& raw, const MeshLoadOptions& options, LoadedMesh& loaded) {
  const long node_count = static_cast<long>(raw.positions.size());
  std::vector<long> inverted_lines;
  for (size_t t = 0; t < raw.tets.size(); ++t) {
    Tet& tet = raw.tets[t];
    for (int v : tet) {
      if (v < 0 || v >= node_count) {
        return Error{where(raw, t) + ": vertex " + std::to_string(v) +
                     (v < 0 ? " is negative" : " >= vertex count " + std::to_string(node_count))};
      }
    }
    for (int i = 0; i < 4; ++i) {
      for (int j = i + 1; j < 4; ++j) {
        if (tet[static_cast<size_t>(i)] == tet[static_cast<size_t>(j)]) {
          return Error{where(raw, t) + ": vertex " + std::to_string(tet[static_cast<size_t>(i)]) +
                       " appears twice"};
        }
      }
    }
    std::array<Eigen::Vector3d, 4> x;
    for (size_t i = 0; i < 4; ++i)
      x[i] = raw.positions[static_cast<size_t>(tet[i])];
    const double six_volume = sixSignedVolume(x[0], x[1], x[2], x[3]);
    const double edge = longestEdge(x);
    if (!std::isfinite(six_volume) || !std::isfinite(edge)) {
      return Error{where(raw, t) + ": coordinates too large: its volume overflows a double"};
    }
    if (std::abs(six_volume) <= options.degenerate_tolerance * edge * edge * edge) {
      std::ostringstream s;
      s << where(raw, t) << ": zero volume (6V = " << six_volume << ", longest edge " << edge
        << "): its four vertices are coplanar";
      return Error{s.str()};
    }
    if (six_volume < 0) {
      if (options.refuse_inverted) {
        return Error{where(raw, t) + ": inverted (negative volume); reorder its vertices, or " +
                     "load without refusing inverted tets to have them reoriented"};
      }
      std::swap(tet[2], tet[3]);
      inverted_lines.push_back(raw.origins[t].line > 0 ? raw.origins[t].line : raw.origins[t].id);
      ++loaded.reoriented_tets;
    }
  }
  if (loaded.reoriented_tets > 0) {
    const bool by_line = raw.origins.front().line > 0;
    std::ostringstream s;
    s << raw.element_file << ": " << loaded.reoriented_tets << " inverted tet"
      << (loaded.reoriented_tets == 1 ? " was" : "s were") << " reoriented ("
      << (by_line ? "line" : "tet") << (inverted_lines.size() == 1 ? " " : "s ");
    for (size_t i = 0; i < std::min<size_t>(inverted_lines.size(), 5); ++i) {
      s << (i ? ", " : "") << inverted_lines[i];
    }
    s << (inverted_lines.size() > 5 ? ", ...)" : ")");
    loaded.warnings.push_back(s.str());
  }
  return Ok{};
}

// The same four nodes twice would pass the face tests below (each face shared by two tets).
Status refuseDuplicateTets(const RawTetMesh& raw) {
  std::vector<std::pair<Tet, size_t>> sorted;
  sorted.reserve(raw.tets.size());
  for (size_t t = 0; t < raw.tets.size(); ++t) {
    Tet key = raw.tets[t];
    std::sort(key.begin(), key.end());
    sorted.emplace_back(key, t);
  }
  std::sort(sorted.begin(), sorted.end());
  for (size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i].first == sorted[i - 1].first) {
      const size_t later = std::max(sorted[i].second, sorted[i - 1].second);
      const size_t earlier = std::min(sorted[i].second, sorted[i - 1].second);
      return Error{where(raw, later) + ": duplicates tet " +
                   std::to_string(raw.origins[earlier].id) + " (the same four vertices)"};
    }
  }
  return Ok{};
}

// A face inside a tet mesh is shared by two tets; three or more means overlapping tets.
Status refuseFacesSharedThrice(const RawTetMesh& raw,
                               const std::vector<detail::FaceRecord>& faces) {
  for (size_t i = 0; i + 2 < faces.size(); ++i) {
    if (faces[i].key == faces[i + 2].key) {
      const auto& k = faces[i].key;
      return Error{where(raw, static_cast<size_t>(faces[i + 2].tet)) + ": face (" +
                   std::to_string(k[0]) + ", " + std::to_string(k[1]) + ", " +
                   std::to_string(k[2]) + ") is already shared by tets " +
                   std::to_string(raw.origins[static_cast<size_t>(faces[i].tet)].id) + " and " +
                   std::to_string(raw.origins[static_cast<size_t>(faces[i + 1].tet)].id) +
                   ": tets overlap or are duplicated"};
    }
  }
  return Ok{};
}

// Two positively oriented tets sharing a face lie on opposite sides of it exactly when they see
// it with opposite orientations. The same orientation puts both on one side: they overlap, even
// though every face is shared only twice (a fuzzer found five tets folded over each other that
// way, leaving no boundary surface at all).
Status refuseTetsOnOneSideOfAFace(const RawTetMesh& raw,
                                  const std::vector<detail::FaceRecord>& faces) {
  for (size_t i = 0; i + 1 < faces.size(); ++i) {
    if (faces[i].key != faces[i + 1].key) continue;
    const auto oriented = [&](const detail::FaceRecord& face) {
      const Tet& tet = raw.tets[static_cast<size_t>(face.tet)];
      const int* local = detail::kOutwardFaces[face.local_face];
      return std::array<int, 3>{tet[static_cast<size_t>(local[0])],
                                tet[static_cast<size_t>(local[1])],
                                tet[static_cast<size_t>(local[2])]};
    };
    const std::array<int, 3> a = oriented(faces[i]);
    const std::array<int, 3> b = oriented(faces[i + 1]);
    // b is a reversed a when it equals one of the three rotations of (a0, a2, a1).
    const bool opposite = (b == std::array<int, 3>{a[0], a[2], a[1]}) ||
                          (b == std::array<int, 3>{a[2], a[1], a[0]}) ||
                          (b == std::array<int, 3>{a[1], a[0], a[2]});
    if (!opposite) {
      const auto& k = faces[i].key;
      const size_t later = static_cast<size_t>(std::max(faces[i].tet, faces[i + 1].tet));
      const size_t earlier = static_cast<size_t>(std::min(faces[i].tet, faces[i + 1].tet));
      return Error{where(raw, later) + ": lies on the same side of face (" + std::to_string(k[0]) +
                   ", " + std::to_string(k[1]) + ", " + std::to_string(k[2]) + ") as tet " +
                   std::to_string(raw.origins[earlier].id) + ": tets overlap"};
    }
  }
  return Ok{};
}

// Nodes no tet uses would have no mass and make the system singular: they are dropped (with a
// warning) and the tets renumbered. Returns the positions that remain.
std::vector<Eigen::Vector3d> dropUnusedNodes(RawTetMesh& raw, LoadedMesh& loaded) {
  std::vector<int> new_index(raw.positions.size(), -1);
  for (const Tet& tet : raw.tets) {
    for (int v : tet)
      new_index[static_cast<size_t>(v)] = 0;
  }
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(raw.positions.size());
  for (size_t n = 0; n < raw.positions.size(); ++n) {
    if (new_index[n] == 0) {
      new_index[n] = static_cast<int>(positions.size());
      positions.push_back(raw.positions[n]);
    }
  }
  const size_t unused = raw.positions.size() - positions.size();
  if (unused > 0) {
    loaded.warnings.push_back(raw.element_file + ": " + std::to_string(unused) + " node" +
                              (unused == 1 ? " is" : "s are") + " used by no tet and " +
                              (unused == 1 ? "was" : "were") + " dropped");
    for (Tet& tet : raw.tets) {
      for (int& v : tet)
        v = new_index[static_cast<size_t>(v)];
    }
  }
  return positions;
}

}  // namespace

Result<LoadedMesh> buildTetMesh(RawTetMesh raw, const MeshLoadOptions& options) {
  numberUnlabelledTets(raw);
  LoadedMesh loaded;
  if (Status s = checkNodes(raw); !s) return s.error();
  if (Status s = checkAndOrientTets(raw, options, loaded); !s) return s.error();
  if (Status s = refuseDuplicateTets(raw); !s) return s.error();
  const std::vector<detail::FaceRecord> faces = detail::sortedFaces(raw.tets);
  if (Status s = refuseFacesSharedThrice(raw, faces); !s) return s.error();
  if (Status s = refuseTetsOnOneSideOfAFace(raw, faces); !s) return s.error();
  std::vector<Eigen::Vector3d> positions = dropUnusedNodes(raw, loaded);
  for (const std::string& note : raw.notes)
    loaded.warnings.push_back(note);
  loaded.mesh = TetMesh(std::move(positions), std::move(raw.tets));
  return loaded;
}

}  // namespace torsion
