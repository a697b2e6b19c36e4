#pragma once
// What every mesh-reader fuzz target checks, whatever the format: a reader either fails with a
// message or returns a RawTetMesh honouring its contract (raw_tet_mesh.h); buildTetMesh then either
// fails with a message or returns a TetMesh whose every documented property holds. Each check is a
// fact that must hold for any input; a violation prints the condition and calls __builtin_trap(),
// which libFuzzer (and replay_main.cpp) report as a crash.

#include <cstddef>
#include <cstdio>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "torsion/mesh/raw_tet_mesh.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/tetgen_format.h"
#include "torsion/result.h"

#define TORSION_FUZZ_CHECK(condition)                                                             \
  do {                                                                                            \
    if (!(condition)) {                                                                           \
      std::fprintf(stderr, "%s:%d: fuzz invariant failed: %s\n", __FILE__, __LINE__, #condition); \
      __builtin_trap();                                                                           \
    }                                                                                             \
  } while (false)

namespace torsion::fuzz {

inline bool startsWith(std::string_view text, std::string_view prefix) {
  return text.substr(0, prefix.size()) == prefix;
}

/// A failure is reported to the user: it must say something, starting with the file it is about.
inline void checkError(const Error& error, std::string_view file) {
  TORSION_FUZZ_CHECK(!error.message.empty());
  TORSION_FUZZ_CHECK(startsWith(error.message, file));
}

/// The reader's side of the contract in raw_tet_mesh.h.
inline void checkRaw(const RawTetMesh& raw) {
  TORSION_FUZZ_CHECK(raw.origins.size() == raw.tets.size());
  for (const Tet& tet : raw.tets) {
    for (int v : tet) {
      TORSION_FUZZ_CHECK(v >= 0 && static_cast<size_t>(v) < raw.positions.size());
    }
  }
}

inline void checkRows(const CompressedRows& rows, int row_count) {
  TORSION_FUZZ_CHECK(rows.rowCount() == row_count);
  TORSION_FUZZ_CHECK(rows.offsets.front() == 0);
  TORSION_FUZZ_CHECK(static_cast<size_t>(rows.offsets.back()) == rows.items.size());
  for (int r = 0; r < row_count; ++r)
    TORSION_FUZZ_CHECK(rows.rowBegin(r) <= rows.rowEnd(r));
}

/// Everything tet_mesh.h promises about a mesh buildTetMesh accepted.
inline void checkMesh(const TetMesh& mesh) {
  const int nodes = mesh.nodeCount();
  const int tets = mesh.tetCount();
  TORSION_FUZZ_CHECK(nodes >= 4);
  TORSION_FUZZ_CHECK(tets > 0);

  for (int t = 0; t < tets; ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    for (size_t i = 0; i < 4; ++i) {
      TORSION_FUZZ_CHECK(tet[i] >= 0 && tet[i] < nodes);
      for (size_t j = i + 1; j < 4; ++j)
        TORSION_FUZZ_CHECK(tet[i] != tet[j]);
    }
    const double volume = mesh.restVolume(t);
    TORSION_FUZZ_CHECK(volume > 0);  // also false for NaN
  }
  TORSION_FUZZ_CHECK(mesh.totalRestVolume() > 0);
  for (const Eigen::Vector3d& p : mesh.restPositions())
    TORSION_FUZZ_CHECK(p.allFinite());
  TORSION_FUZZ_CHECK((mesh.boundsMin().array() <= mesh.boundsMax().array()).all());

  // Boundary faces = 4 * tets - 2 * interior faces, so their number is even; each surface edge is
  // shared by an even number (>= 2) of surface triangles, so a triangle has >= 3 neighbours, and a
  // bounded body has a non-empty boundary.
  const int triangles = mesh.surfaceTriangleCount();
  TORSION_FUZZ_CHECK(triangles % 2 == 0);
  TORSION_FUZZ_CHECK(triangles >= 4);
  TORSION_FUZZ_CHECK(triangles <= 4 * tets);
  TORSION_FUZZ_CHECK(mesh.surfaceTriangleTets().size() == static_cast<size_t>(triangles));
  for (int s = 0; s < triangles; ++s) {
    const Triangle& tri = mesh.surfaceTriangles()[static_cast<size_t>(s)];
    const int owner = mesh.surfaceTriangleTets()[static_cast<size_t>(s)];
    TORSION_FUZZ_CHECK(owner >= 0 && owner < tets);
    const Tet& tet = mesh.tets()[static_cast<size_t>(owner)];
    for (size_t i = 0; i < 3; ++i) {
      TORSION_FUZZ_CHECK(tri[i] >= 0 && tri[i] < nodes);
      TORSION_FUZZ_CHECK(tri[i] != tri[(i + 1) % 3]);
      TORSION_FUZZ_CHECK(tri[i] == tet[0] || tri[i] == tet[1] || tri[i] == tet[2] ||
                         tri[i] == tet[3]);
    }
  }

  const CompressedRows& neighbours = mesh.surfaceTriangleNeighbours();
  checkRows(neighbours, triangles);
  for (int s = 0; s < triangles; ++s) {
    TORSION_FUZZ_CHECK(neighbours.rowEnd(s) - neighbours.rowBegin(s) >= 3);
    for (int k = neighbours.rowBegin(s); k < neighbours.rowEnd(s); ++k) {
      const int other = neighbours.items[static_cast<size_t>(k)];
      TORSION_FUZZ_CHECK(other >= 0 && other < triangles && other != s);
    }
  }

  const std::vector<int>& surface_nodes = mesh.surfaceNodes();
  TORSION_FUZZ_CHECK(surface_nodes.size() >= 4);
  for (size_t i = 0; i < surface_nodes.size(); ++i) {
    TORSION_FUZZ_CHECK(surface_nodes[i] >= 0 && surface_nodes[i] < nodes);
    if (i > 0) TORSION_FUZZ_CHECK(surface_nodes[i - 1] < surface_nodes[i]);
  }

  // Unused nodes were dropped, so every node belongs to a tet.
  const CompressedRows& node_tets = mesh.nodeTets();
  checkRows(node_tets, nodes);
  TORSION_FUZZ_CHECK(node_tets.items.size() == 4 * static_cast<size_t>(tets));
  for (int n = 0; n < nodes; ++n) {
    TORSION_FUZZ_CHECK(node_tets.rowBegin(n) < node_tets.rowEnd(n));
    for (int k = node_tets.rowBegin(n); k < node_tets.rowEnd(n); ++k) {
      const int t = node_tets.items[static_cast<size_t>(k)];
      TORSION_FUZZ_CHECK(t >= 0 && t < tets);
      if (k > node_tets.rowBegin(n))
        TORSION_FUZZ_CHECK(node_tets.items[static_cast<size_t>(k - 1)] < t);
      const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
      TORSION_FUZZ_CHECK(tet[0] == n || tet[1] == n || tet[2] == n || tet[3] == n);
    }
  }
}

/// formatTetGen writes with round-trip precision, so reading its output back must give the very
/// same mesh, with nothing to reorient or drop.
inline void checkTetGenRoundTrip(const TetMesh& mesh) {
  const TetGenText text = formatTetGen(mesh);
  Result<RawTetMesh> raw = parseTetGen(text.node, "roundtrip.node", text.ele, "roundtrip.ele");
  TORSION_FUZZ_CHECK(raw.ok());
  Result<LoadedMesh> again = buildTetMesh(std::move(raw).value());
  TORSION_FUZZ_CHECK(again.ok());
  TORSION_FUZZ_CHECK(again.value().reoriented_tets == 0);
  TORSION_FUZZ_CHECK(again.value().warnings.empty());
  TORSION_FUZZ_CHECK(again.value().mesh.restPositions() == mesh.restPositions());
  TORSION_FUZZ_CHECK(again.value().mesh.tets() == mesh.tets());
}

/// Checks a reader's successful result, then validates it with buildTetMesh and checks that.
inline void buildAndCheck(RawTetMesh raw) {
  checkRaw(raw);
  const size_t raw_nodes = raw.positions.size();
  const size_t raw_tets = raw.tets.size();
  const std::string element_file = raw.element_file;

  MeshLoadOptions refuse;
  refuse.refuse_inverted = true;
  Result<LoadedMesh> strict = buildTetMesh(raw, refuse);
  if (!strict.ok()) checkError(strict.error(), element_file);

  Result<LoadedMesh> loaded = buildTetMesh(std::move(raw));
  if (!loaded.ok()) {
    checkError(loaded.error(), element_file);
    TORSION_FUZZ_CHECK(!strict.ok());  // refusing inverted tets only refuses more
    return;
  }
  const LoadedMesh& result = loaded.value();
  const TetMesh& mesh = result.mesh;
  // Tets are never dropped; nodes only when no tet uses them.
  TORSION_FUZZ_CHECK(static_cast<size_t>(mesh.tetCount()) == raw_tets);
  TORSION_FUZZ_CHECK(static_cast<size_t>(mesh.nodeCount()) <= raw_nodes);
  TORSION_FUZZ_CHECK(result.reoriented_tets >= 0 && result.reoriented_tets <= mesh.tetCount());
  if (result.reoriented_tets > 0 || static_cast<size_t>(mesh.nodeCount()) < raw_nodes) {
    TORSION_FUZZ_CHECK(!result.warnings.empty());
  }
  // The option changes nothing but the handling of inverted tets.
  TORSION_FUZZ_CHECK(strict.ok() == (result.reoriented_tets == 0));
  if (strict.ok()) {
    TORSION_FUZZ_CHECK(strict.value().mesh.tets() == mesh.tets());
    TORSION_FUZZ_CHECK(strict.value().mesh.restPositions() == mesh.restPositions());
  }

  checkMesh(mesh);
  checkTetGenRoundTrip(mesh);
}

}  // namespace torsion::fuzz
