#include "structured_mesh_command.h"

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "cli_messages.h"
#include "torsion/mesh/ball_mesh.h"
#include "torsion/mesh/box_mesh.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::cli {

namespace {

struct BoxOptions {
  std::vector<double> min, max;
  std::vector<int> cells;
  std::string output;
};

struct BallOptions {
  double radius = 0;
  int cells = 0;
  std::vector<double> center{0, 0, 0};
  std::string output;
};

int write(const std::string& command, const Result<TetMesh>& mesh, const std::string& output,
          const std::string& what) {
  if (!mesh) return fail(command + mesh.error().message);
  Result<MeshFormat> format = meshFormatOf(output);
  if (!format) return fail(format.error().message);
  Status written = writeMesh(output, mesh.value());
  if (!written) return fail(written.error().message);
  std::printf("wrote %s: %s, %d tets, %d nodes, %d surface triangles\n", output.c_str(),
              what.c_str(), mesh.value().tetCount(), mesh.value().nodeCount(),
              mesh.value().surfaceTriangleCount());
  return 0;
}

int runBox(const BoxOptions& o) {
  const std::string cmd = "torsion mesh box: ";
  const Eigen::Vector3d lo(o.min[0], o.min[1], o.min[2]), hi(o.max[0], o.max[1], o.max[2]);
  if (!(hi.array() > lo.array()).all() || !lo.allFinite() || !hi.allFinite())
    return fail(cmd + "--max must exceed --min on every axis");
  for (int c : o.cells) {
    if (c < 1 || c > 200) return fail(cmd + "--cells must be between 1 and 200 per axis");
  }
  char what[160];
  std::snprintf(what, sizeof what, "box [%g %g %g] to [%g %g %g], %d x %d x %d cells", lo.x(),
                lo.y(), lo.z(), hi.x(), hi.y(), hi.z(), o.cells[0], o.cells[1], o.cells[2]);
  return write(cmd, makeBoxTetMesh(lo, hi, o.cells[0], o.cells[1], o.cells[2]), o.output, what);
}

int runBall(const BallOptions& o) {
  const std::string cmd = "torsion mesh ball: ";
  if (o.cells < 2 || o.cells > 100) return fail(cmd + "--cells must be between 2 and 100");
  const Eigen::Vector3d c(o.center[0], o.center[1], o.center[2]);
  char what[160];
  std::snprintf(what, sizeof what, "ball radius %g at [%g %g %g], %d cells per side", o.radius,
                c.x(), c.y(), c.z(), o.cells);
  return write(cmd, makeBallTetMesh(c, o.radius, o.cells), o.output, what);
}

}  // namespace

void addStructuredMeshCommands(CLI::App& mesh, CommandAction& chosen) {
  auto box = std::make_shared<BoxOptions>();
  CLI::App* box_cmd = mesh.add_subcommand(
      "box", "Mesh an axis-aligned box with a structured grid (each cell split into 6 tets)");
  box_cmd->add_option("--min", box->min, "Lower corner x y z (m)")->required()->expected(3);
  box_cmd->add_option("--max", box->max, "Upper corner x y z (m)")->required()->expected(3);
  box_cmd->add_option("--cells", box->cells, "Cells along x y z")->required()->expected(3);
  box_cmd->add_option("-o,--output", box->output, "Mesh to write (.node/.ele, .msh, .vtk)")
      ->required();
  box_cmd->callback([&chosen, box] { chosen = [box] { return runBox(*box); }; });

  auto ball = std::make_shared<BallOptions>();
  CLI::App* ball_cmd = mesh.add_subcommand(
      "ball", "Mesh a ball: a structured cube mesh with every node pulled onto the ball");
  ball_cmd->add_option("--radius", ball->radius, "Radius (m)")->required();
  ball_cmd->add_option("--cells", ball->cells, "Cells per side of the cube it is made from")
      ->required();
  ball_cmd->add_option("--center", ball->center, "Centre x y z (m), default 0 0 0")->expected(3);
  ball_cmd->add_option("-o,--output", ball->output, "Mesh to write (.node/.ele, .msh, .vtk)")
      ->required();
  ball_cmd->callback([&chosen, ball] { chosen = [ball] { return runBall(*ball); }; });
}

}  // namespace torsion::cli
