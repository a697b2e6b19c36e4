#include "mesh_command.h"

#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_messages.h"
#include "mesh_generate_command.h"
#include "structured_mesh_command.h"
#include "torsion/mesh/mesh_io.h"
#include "torsion/mesh/mesh_quality.h"
#include "torsion/mesh/node_ordering.h"

namespace torsion::cli {

namespace {

struct InfoOptions {
  std::string file;
  bool refuse_inverted = false;
};

struct ConvertOptions {
  std::string input;
  std::string output;
  bool refuse_inverted = false;
  bool reorder = false;  // renumber the nodes in reverse Cuthill-McKee order
};

int runInfo(const InfoOptions& options) {
  Result<LoadedMesh> loaded = readMesh(options.file, {options.refuse_inverted});
  if (!loaded) {
    std::cerr << "error: " << loaded.error().message << "\n";
    return 1;
  }
  printWarnings(loaded.value());
  const TetMesh& mesh = loaded.value().mesh;
  const MeshQuality q = measureQuality(mesh, mesh.restPositions());
  const Eigen::Vector3d lo = mesh.boundsMin(), hi = mesh.boundsMax();
  std::printf("file              %s\n", options.file.c_str());
  std::printf("nodes             %d\n", mesh.nodeCount());
  std::printf("tets              %d\n", mesh.tetCount());
  std::printf("surface triangles %d\n", mesh.surfaceTriangleCount());
  std::printf("surface nodes     %zu\n", mesh.surfaceNodes().size());
  std::printf("volume            %.6g\n", mesh.totalRestVolume());
  std::printf("bounds min        %.6g %.6g %.6g\n", lo.x(), lo.y(), lo.z());
  std::printf("bounds max        %.6g %.6g %.6g\n", hi.x(), hi.y(), hi.z());
  std::printf("dihedral min/max  %.3f / %.3f deg\n", q.min_dihedral_deg, q.max_dihedral_deg);
  std::printf("aspect max/mean   %.3f / %.3f\n", q.max_aspect_ratio, q.mean_aspect_ratio);
  std::printf("inverted in file  %d (reoriented)\n", loaded.value().reoriented_tets);
  return 0;
}

int runConvert(const ConvertOptions& options) {
  Result<LoadedMesh> loaded = readMesh(options.input, {options.refuse_inverted});
  if (!loaded) {
    std::cerr << "error: " << loaded.error().message << "\n";
    return 1;
  }
  printWarnings(loaded.value());
  const TetMesh& read = loaded.value().mesh;
  const TetMesh mesh = options.reorder ? inCacheFriendlyOrder(read) : read;
  Status written = writeMesh(options.output, mesh);
  if (!written) {
    std::cerr << "error: " << written.error().message << "\n";
    return 1;
  }
  std::printf("wrote %s (%d nodes, %d tets)\n", options.output.c_str(), mesh.nodeCount(),
              mesh.tetCount());
  if (options.reorder) {
    std::printf("node order        reverse Cuthill-McKee: mean index span per tet %.1f -> %.1f\n",
                meanTetIndexSpan(read), meanTetIndexSpan(mesh));
  }
  return 0;
}

}  // namespace

void addMeshCommand(CLI::App& app, CommandAction& chosen) {
  CLI::App* mesh = app.add_subcommand("mesh", "Inspect, convert and generate tetrahedral meshes");
  mesh->require_subcommand(1);

  auto info = std::make_shared<InfoOptions>();
  CLI::App* info_cmd =
      mesh->add_subcommand("info", "Counts, volume, bounds and element quality of a mesh");
  info_cmd->add_option("file", info->file, "Mesh file (.node/.ele, .msh, .vtk)")->required();
  info_cmd->add_flag("--refuse-inverted", info->refuse_inverted,
                     "Fail on inverted tets instead of reorienting them");
  info_cmd->callback([&chosen, info] { chosen = [info] { return runInfo(*info); }; });

  auto convert = std::make_shared<ConvertOptions>();
  CLI::App* convert_cmd = mesh->add_subcommand(
      "convert", "Convert between mesh formats (by extension: .node/.ele, .msh, .vtk)");
  convert_cmd->add_option("input", convert->input, "Mesh to read")->required();
  convert_cmd->add_option("output", convert->output, "Mesh to write")->required();
  convert_cmd->add_flag(
      "--reorder", convert->reorder,
      "Renumber the nodes in reverse Cuthill-McKee order, so that nodes sharing a "
      "tet get nearby numbers and every pass of a step stays in cache (node ids "
      "change: select node sets by geometry)");
  convert_cmd->add_flag("--refuse-inverted", convert->refuse_inverted,
                        "Fail on inverted tets instead of reorienting them");
  convert_cmd->callback(
      [&chosen, convert] { chosen = [convert] { return runConvert(*convert); }; });

  addMeshGenerateCommands(*mesh, chosen);
  addStructuredMeshCommands(*mesh, chosen);
}

}  // namespace torsion::cli
