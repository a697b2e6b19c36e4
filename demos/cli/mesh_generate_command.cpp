#include "mesh_generate_command.h"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "cli_messages.h"
#include "cylinder_mesher.h"
#include "gmsh_runner.h"
#include "surface_mesh.h"
#include "tetgen_runner.h"
#include "torsion/mesh/mesh_io.h"
#include "torsion/mesh/node_ordering.h"

namespace torsion::cli {

namespace {

namespace fs = std::filesystem;
using meshgen::CylinderMesh;
using meshgen::CylinderSpec;
using meshgen::SurfaceMesh;
using meshgen::TempDir;
using meshgen::TetgenRun;

constexpr int kMaxTets = 20'000'000;
constexpr double kTolerancePercent = 3.0;  // cylinder: |tets - target| / target

struct CylinderOptions {
  double radius = 0;
  double length = 0;
  long tets = 0;
  std::string output;
  std::string mesher = "tetgen";
  bool verbose = false;
};

// Without --max-volume, tets are sized from the surface: edges about 1/10 of its bounding box's
// diagonal (the volume of a regular tet of that edge: a few thousand tets for a cube), so a small
// part and a large one get about the same number of tets.
constexpr double kDefaultEdgesPerDiagonal = 10;

struct TetrahedralizeOptions {
  std::string surface;
  std::string output;
  std::string mesher = "tetgen";
  double max_volume = -1;  // < 0: from the surface's size; 0: no bound
  double quality = 1.4;
  double min_dihedral = 0;
  bool keep_surface = false;
  bool verbose = false;
};

std::string number(double x) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.6g", x);
  return buffer;
}

int runCylinder(const CylinderOptions& o) {
  const std::string cmd = "torsion mesh cylinder: ";
  if (!(o.radius > 0) || !std::isfinite(o.radius)) {
    return fail(cmd + "--radius must be a positive number, got " + number(o.radius));
  }
  if (!(o.length > 0) || !std::isfinite(o.length)) {
    return fail(cmd + "--length must be a positive number, got " + number(o.length));
  }
  if (o.tets < 6 || o.tets > kMaxTets) {
    return fail(cmd + "--tets must be between 6 and " + std::to_string(kMaxTets) + ", got " +
                std::to_string(o.tets));
  }
  if (o.mesher != "tetgen") {
    return fail(cmd + "unknown --mesher '" + o.mesher + "' (known: tetgen)");
  }
  Result<MeshFormat> format = meshFormatOf(o.output);
  if (!format) return fail(format.error().message);

  Result<fs::path> tetgen = meshgen::findTetgen("cylinder");
  if (!tetgen) return fail(tetgen.error().message);
  Result<TempDir> dir = TempDir::create("torsion-cylinder");
  if (!dir) return fail(dir.error().message);

  CylinderSpec spec{o.radius, o.length, static_cast<int>(o.tets)};
  Result<CylinderMesh> made = meshgen::meshCylinder(tetgen.value(), spec, dir.value().path(),
                                                    o.verbose ? &std::cout : nullptr);
  if (!made) return fail(cmd + made.error().message);
  const CylinderMesh& cyl = made.value();
  // Tetgen numbers nodes as it inserts them; nearby numbers for nodes that share a tet make
  // every pass of a step cache-friendly (mesh/node_ordering.h).
  const TetMesh mesh = inCacheFriendlyOrder(cyl.mesh.mesh);
  const double off =
      100.0 * static_cast<double>(mesh.tetCount() - o.tets) / static_cast<double>(o.tets);
  if (std::abs(off) > kTolerancePercent) {
    char message[320];
    std::snprintf(message, sizeof message,
                  "could not get within %.0f%% of %ld tets: the closest count found was %d "
                  "(%+.1f%%, %d segments x %d layers, %d tetgen runs); tetgen's quality bound "
                  "makes some counts unreachable, in particular few tets for a flat or slender "
                  "cylinder: try another --tets",
                  kTolerancePercent, o.tets, mesh.tetCount(), off, cyl.segments, cyl.layers,
                  cyl.runs);
    return fail(cmd + message);
  }
  printWarnings(cyl.mesh);
  Status written = writeMesh(o.output, mesh);
  if (!written) return fail(written.error().message);
  std::printf(
      "wrote %s: cylinder radius %s length %s, %d tets (target %ld, %+.1f%%), %d nodes, "
      "%d surface triangles\n",
      o.output.c_str(), number(o.radius).c_str(), number(o.length).c_str(), mesh.tetCount(), o.tets,
      off, mesh.nodeCount(), mesh.surfaceTriangleCount());
  std::printf("made by: tetgen %s on a %d-segment x %d-layer surface (%d tetgen runs)\n",
              cyl.switches.c_str(), cyl.segments, cyl.layers, cyl.runs);
  return 0;
}

std::string tetrahedralizeSwitches(const TetrahedralizeOptions& o) {
  std::string s = "-pq" + number(o.quality);
  if (o.min_dihedral > 0) s += "/" + number(o.min_dihedral);
  if (o.max_volume > 0) s += "a" + number(o.max_volume);
  if (o.keep_surface) s += "Y";
  return s + "FQ";
}

// After tetgen failed: ask `tetgen -d` whether the surface intersects itself and name the lines.
std::string intersectionReport(const fs::path& tetgen, const fs::path& input,
                               const SurfaceMesh& surface, const std::string& file) {
  Result<std::vector<std::pair<int, int>>> pairs = meshgen::findSelfIntersections(tetgen, input);
  if (!pairs || pairs.value().empty()) return "";
  auto name = [&](int t) {
    const size_t i = static_cast<size_t>(t);
    if (t >= 0 && i < surface.triangle_lines.size() && surface.triangle_lines[i] > 0) {
      return file + ":" + std::to_string(surface.triangle_lines[i]);
    }
    return file + " triangle " + std::to_string(t);
  };
  const auto& p = pairs.value();
  std::string report = "\n" + file + ": the surface intersects itself (tetgen -d found " +
                       std::to_string(p.size()) + " intersecting triangle pair" +
                       (p.size() == 1 ? "" : "s") + "), e.g.:";
  for (size_t k = 0; k < p.size() && k < 5; ++k) {
    report += "\n  " + name(p[k].first) + " and " + name(p[k].second);
  }
  return report;
}

// The volume of a regular tet with edge `edge`, and the edge of one with volume `volume`.
double regularTetVolume(double edge) {
  return edge * edge * edge / (6 * std::sqrt(2.0));
}
double regularTetEdge(double volume) {
  return std::cbrt(6 * std::sqrt(2.0) * volume);
}

int runGmshTetrahedralize(const TetrahedralizeOptions& o, const SurfaceMesh& surface) {
  const std::string cmd = "torsion mesh tetrahedralize: ";
  Result<fs::path> gmsh = meshgen::findGmsh("tetrahedralize");
  if (!gmsh) return fail(gmsh.error().message);
  Result<TempDir> dir = TempDir::create("torsion-tetrahedralize");
  if (!dir) return fail(dir.error().message);
  const double edge = o.max_volume > 0 ? regularTetEdge(o.max_volume) : 0.0;
  if (o.verbose) {
    std::printf("%s: %zu vertices, %zu triangles; running gmsh -3 (longest edge %s)\n",
                o.surface.c_str(), surface.vertices.size(), surface.triangles.size(),
                edge > 0 ? number(edge).c_str() : "gmsh's default");
  }
  Result<fs::path> msh = meshgen::runGmsh(gmsh.value(), surface, edge, dir.value().path());
  if (!msh) return fail(cmd + o.surface + ": " + msh.error().message);
  Result<LoadedMesh> loaded = readMesh(msh.value());
  if (!loaded) return fail(cmd + "reading gmsh's output: " + loaded.error().message);
  const TetMesh mesh = inCacheFriendlyOrder(loaded.value().mesh);  // mesh/node_ordering.h
  Status written = writeMesh(o.output, mesh);
  if (!written) return fail(written.error().message);
  std::printf(
      "wrote %s: %d tets, %d nodes, %d surface triangles (from %s: %zu vertices, %zu "
      "triangles; gmsh, longest edge %s)\n",
      o.output.c_str(), mesh.tetCount(), mesh.nodeCount(), mesh.surfaceTriangleCount(),
      o.surface.c_str(), surface.vertices.size(), surface.triangles.size(),
      edge > 0 ? number(edge).c_str() : "gmsh's default");
  return 0;
}

int runTetrahedralize(TetrahedralizeOptions o) {
  const std::string cmd = "torsion mesh tetrahedralize: ";
  if (!std::isfinite(o.max_volume)) {
    return fail(cmd + "--max-volume must be a positive number, got " + number(o.max_volume));
  }
  if (o.mesher != "tetgen" && o.mesher != "gmsh") {
    return fail(cmd + "--mesher must be tetgen or gmsh, got '" + o.mesher + "'");
  }
  if (!(o.quality >= 1.1) || !std::isfinite(o.quality)) {
    return fail(cmd + "--quality (radius-edge ratio bound) must be at least 1.1, got " +
                number(o.quality) + " (tetgen may not terminate below that)");
  }
  if (!(o.min_dihedral >= 0 && o.min_dihedral <= 20)) {
    return fail(cmd + "--min-dihedral must be between 0 and 20 degrees, got " +
                number(o.min_dihedral) + " (tetgen may not terminate above that)");
  }
  Result<MeshFormat> format = meshFormatOf(o.output);
  if (!format) return fail(format.error().message);

  Result<SurfaceMesh> read = meshgen::readSurface(o.surface);
  if (!read) return fail(read.error().message);
  SurfaceMesh surface = std::move(read).value();
  Status closed = meshgen::prepareClosedSurface(surface, o.surface);
  if (!closed) return fail(closed.error().message);
  if (o.max_volume < 0) {  // not given: from the surface's size
    Eigen::Vector3d lo = surface.vertices.front(), hi = lo;
    for (const Eigen::Vector3d& v : surface.vertices) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
    o.max_volume = regularTetVolume((hi - lo).norm() / kDefaultEdgesPerDiagonal);
  }
  if (o.mesher == "gmsh") return runGmshTetrahedralize(o, surface);

  Result<fs::path> tetgen = meshgen::findTetgen("tetrahedralize");
  if (!tetgen) return fail(tetgen.error().message);
  Result<TempDir> dir = TempDir::create("torsion-tetrahedralize");
  if (!dir) return fail(dir.error().message);
  const fs::path input = dir.value().path() / "surface.smesh";
  Status staged = writeTextFile(input, meshgen::formatSmesh(surface, "from " + o.surface));
  if (!staged) return fail(staged.error().message);

  const std::string switches = tetrahedralizeSwitches(o);
  if (o.verbose) {
    std::printf("%s: %zu vertices, %zu triangles; running tetgen %s\n", o.surface.c_str(),
                surface.vertices.size(), surface.triangles.size(), switches.c_str());
  }
  Result<TetgenRun> run = meshgen::runTetgen(tetgen.value(), switches, input);
  if (!run) {
    return fail(cmd + o.surface + ": " + run.error().message +
                intersectionReport(tetgen.value(), input, surface, o.surface));
  }
  Result<LoadedMesh> loaded = readMesh(run.value().node);
  if (!loaded) return fail(cmd + "reading tetgen's output: " + loaded.error().message);
  printWarnings(loaded.value());
  const TetMesh mesh = inCacheFriendlyOrder(loaded.value().mesh);  // mesh/node_ordering.h
  Status written = writeMesh(o.output, mesh);
  if (!written) return fail(written.error().message);
  std::printf(
      "wrote %s: %d tets, %d nodes, %d surface triangles (from %s: %zu vertices, %zu "
      "triangles; tetgen %s)\n",
      o.output.c_str(), mesh.tetCount(), mesh.nodeCount(), mesh.surfaceTriangleCount(),
      o.surface.c_str(), surface.vertices.size(), surface.triangles.size(), switches.c_str());
  return 0;
}

}  // namespace

void addMeshGenerateCommands(CLI::App& mesh, CommandAction& chosen) {
  auto cyl = std::make_shared<CylinderOptions>();
  CLI::App* cyl_cmd = mesh.add_subcommand(
      "cylinder",
      "Mesh a solid cylinder along +z (axis x = y = 0, z from 0 to the length) with about N tets, "
      "using the 'tetgen' command");
  cyl_cmd->add_option("--radius", cyl->radius, "Radius (m)")->required();
  cyl_cmd->add_option("--length", cyl->length, "Length along +z (m)")->required();
  cyl_cmd->add_option("--tets", cyl->tets, "Number of tets to aim for (gets within 3% or fails)")
      ->required();
  cyl_cmd->add_option("-o,--output", cyl->output, "Mesh to write (.node/.ele, .msh, .vtk)")
      ->required();
  cyl_cmd->add_option("--mesher", cyl->mesher, "Mesh generator (only 'tetgen')")
      ->capture_default_str();
  cyl_cmd->add_flag("-v,--verbose", cyl->verbose, "Print every tetgen run of the search");
  cyl_cmd->callback([&chosen, cyl] { chosen = [cyl] { return runCylinder(*cyl); }; });

  auto tet = std::make_shared<TetrahedralizeOptions>();
  CLI::App* tet_cmd = mesh.add_subcommand("tetrahedralize",
                                          "Fill a closed triangle surface (.off, .obj, .stl, .ply) "
                                          "with tets, using the 'tetgen' (default) "
                                          "or 'gmsh' command");
  tet_cmd->add_option("surface", tet->surface, "Closed surface (.off, .obj, .stl, .ply)")
      ->required();
  tet_cmd->add_option("-o,--output", tet->output, "Mesh to write (.node/.ele, .msh, .vtk)")
      ->required();
  tet_cmd->add_option("--max-volume", tet->max_volume,
                      "Largest tet volume (tetgen -a; gmsh: the edge of a regular tet of that "
                      "volume); default: that of a regular tet with edges 1/10 of the surface's "
                      "bounding-box diagonal; 0: no bound");
  tet_cmd->add_option("--mesher", tet->mesher, "Mesh generator: tetgen or gmsh")
      ->check(CLI::IsMember({"tetgen", "gmsh"}))
      ->capture_default_str();
  tet_cmd
      ->add_option("--quality", tet->quality, "Radius-edge ratio bound (tetgen -q), at least 1.1")
      ->capture_default_str();
  tet_cmd
      ->add_option("--min-dihedral", tet->min_dihedral,
                   "Minimum dihedral angle in degrees (tetgen -q.../D), 0: tetgen's default")
      ->capture_default_str();
  tet_cmd->add_flag("--keep-surface", tet->keep_surface,
                    "Do not add points on the surface (tetgen -Y)");
  tet_cmd->add_flag("-v,--verbose", tet->verbose, "Print the tetgen command line");
  tet_cmd->callback([&chosen, tet] { chosen = [tet] { return runTetrahedralize(*tet); }; });
}

}  // namespace torsion::cli
