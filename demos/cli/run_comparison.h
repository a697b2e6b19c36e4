#pragma once
// Compares two `torsion run` output directories: a run against a reference run (`torsion check`).
// What is compared, and how (docs/outputs.md, "Comparing two runs"):
//   summary.json  every value that describes the result: strings and booleans exactly, numbers
//                 within the tolerance; values that describe how it was obtained (version, commit,
//                 threads, solver and its iterations, timings, state hash) are shown when they
//                 differ but are not differences
//   wrench.csv, energy.csv, rigid.csv   same header and rows; each number within the tolerance
//                 of its kind's scale: the largest magnitude in the reference file among the
//                 columns of its kind (forces, torques, energies, positions, orientations,
//                 velocities; any other column alone), so a force that passes through zero, or a
//                 fixed base that carries no load, is judged against the forces of the run
//   <body>.vtk    the final node positions within the tolerance of the body's size (the diagonal
//                 of its bounding box in the reference)
// A value passes when |run - reference| <= relative * scale + absolute.

#include <string>
#include <vector>

#include "torsion/result.h"

namespace torsion::cli {

struct ComparisonTolerance {
  double relative = 1e-6;   ///< of each value's scale
  double absolute = 1e-12;  ///< in the value's own unit, for quantities that are zero throughout
};

struct RunComparison {
  std::vector<std::string> report;  ///< readable lines, one per file then one per finding
  int differences = 0;              ///< values outside the tolerance, missing files and keys
};

/// Errors only when a directory holds no readable summary.json or a file cannot be parsed.
Result<RunComparison> compareRuns(const std::string& run_directory,
                                  const std::string& reference_directory,
                                  const ComparisonTolerance& tolerance);

}  // namespace torsion::cli
