#pragma once
// `torsion check RUN_DIR REFERENCE_DIR [--tolerance R] [--absolute-tolerance A]`: compares a run's
// outputs with a reference run's (run_comparison.h), prints a report and exits 0 when they agree
// within the tolerance, 2 when they differ, 1 when a directory cannot be read.

#include <CLI/CLI.hpp>

#include "command_action.h"

namespace torsion::cli {

void addCheckCommand(CLI::App& app, CommandAction& chosen);

}  // namespace torsion::cli
