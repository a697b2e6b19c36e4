#pragma once
// A solid cylinder along +z (axis x = y = 0, from z = 0 to z = length) meshed by tetgen with about
// a requested number of tets: the surface is a PLC of rings (side quads, two cap polygons) whose
// spacing and tetgen's maximum tet volume are searched until the count is close to the target.

#include <filesystem>
#include <iosfwd>
#include <string>

#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/result.h"

namespace torsion::meshgen {

struct CylinderSpec {
  double radius = 1;
  double length = 10;
  int target_tets = 1000;
};

struct CylinderMesh {
  LoadedMesh mesh;
  int segments = 0;       ///< points per ring (around the axis)
  int layers = 0;         ///< rings - 1 (along the axis)
  double max_volume = 0;  ///< tetgen -a
  std::string switches;   ///< the tetgen switches of the run that made it
  int runs = 0;           ///< tetgen runs the search took
};

/// The tetgen switches for the cylinder: quality (radius-edge ratio 1.4, min dihedral 12 deg) and
/// the max volume.
std::string cylinderSwitches(double max_volume);

/// TetGen .smesh text of the cylinder surface with `segments` points per ring and `layers` + 1
/// rings; facets: the two caps (one polygon each) and segments * layers side quads.
std::string cylinderSmesh(double radius, double length, int segments, int layers);

/// Searches surface spacing and max volume (deterministically: the same spec gives the same mesh)
/// for a count within 1% of the target, at most ~40 tetgen runs, and returns the closest mesh
/// found. `log` (may be null) receives one line per tetgen run.
Result<CylinderMesh> meshCylinder(const std::filesystem::path& tetgen, const CylinderSpec& spec,
                                  const std::filesystem::path& work_dir, std::ostream* log);

}  // namespace torsion::meshgen
