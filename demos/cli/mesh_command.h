#pragma once
// `torsion mesh ...`: inspect, convert and generate tetrahedral meshes.

#include <CLI/CLI.hpp>

namespace torsion::cli {

/// Registers `mesh` and its subcommands (info, convert, cylinder, tetrahedralize).
void addMeshCommand(CLI::App& app);

/// The exit code of the subcommand that ran (0 success, 1 bad input or failure).
int exitCode();
/// Records the exit code of the subcommand that ran.
void setExitCode(int code);

}  // namespace torsion::cli
