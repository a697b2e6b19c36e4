#include "gmsh_runner.h"

#include <cstdio>
#include <sstream>

#include "tetgen_runner.h"
#include "torsion/mesh/mesh_io.h"

namespace torsion::meshgen {

namespace fs = std::filesystem;

Result<fs::path> findGmsh(std::string_view command) {
  fs::path gmsh = findOnPath("gmsh");
  if (gmsh.empty()) {
    return Error{"torsion mesh " + std::string(command) +
                 ": needs the 'gmsh' command (Debian package 'gmsh'); it is not on PATH"};
  }
  return gmsh;
}

namespace {

std::string asciiStl(const SurfaceMesh& surface) {
  std::ostringstream stl;
  stl.precision(17);
  stl << "solid surface\n";
  for (const auto& t : surface.triangles) {
    stl << "facet normal 0 0 0\nouter loop\n";
    for (int v : t) {
      const Eigen::Vector3d& p = surface.vertices[static_cast<size_t>(v)];
      stl << "vertex " << p.x() << " " << p.y() << " " << p.z() << "\n";
    }
    stl << "endloop\nendfacet\n";
  }
  stl << "endsolid surface\n";
  return stl.str();
}

}  // namespace

Result<fs::path> runGmsh(const fs::path& gmsh, const SurfaceMesh& surface, double max_edge,
                         const fs::path& dir) {
  if (Status s = writeTextFile(dir / "surface.stl", asciiStl(surface)); !s) return s.error();
  std::ostringstream geo;
  geo.precision(17);
  geo << "Merge \"surface.stl\";\n"
      << "ClassifySurfaces{40 * Pi / 180, 1, 1, Pi};\n"
      << "CreateGeometry;\n"
      << "Surface Loop(1) = Surface{:};\n"
      << "Volume(1) = {1};\n";
  if (max_edge > 0) geo << "Mesh.MeshSizeMax = " << max_edge << ";\n";
  if (Status s = writeTextFile(dir / "volume.geo", geo.str()); !s) return s.error();
  const fs::path msh = dir / "volume.msh";
  Result<ProcessResult> run = runProcess(
      {gmsh.string(), "-3", "-format", "msh22", "-o", msh.string(), (dir / "volume.geo").string()},
      dir);
  if (!run) return run.error();
  std::error_code ec;
  if (!run.value().exited || run.value().exit_code != 0 || !fs::exists(msh, ec)) {
    std::string said = run.value().err.empty() ? run.value().out : run.value().err;
    if (said.size() > 600) said = "..." + said.substr(said.size() - 600);
    return Error{"gmsh failed (" +
                 (run.value().exited ? "exit status " + std::to_string(run.value().exit_code)
                                     : std::string("killed by a signal")) +
                 "):\n" + said};
  }
  return msh;
}

}  // namespace torsion::meshgen
