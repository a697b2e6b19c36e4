#pragma once
// `torsion mesh ...`: inspect, convert and generate tetrahedral meshes.

#include <CLI/CLI.hpp>

#include "command_action.h"

namespace torsion::cli {

/// Registers `mesh` and its subcommands (info, convert, box, ball, cylinder, tetrahedralize); the
/// one the command line names is put into `chosen`.
void addMeshCommand(CLI::App& app, CommandAction& chosen);

}  // namespace torsion::cli
