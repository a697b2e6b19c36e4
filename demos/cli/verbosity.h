#pragma once
// How much the torsion tool says on stderr: `--quiet` only warnings and errors, the default also
// what it loaded and its progress, `--verbose` also the settings it resolved. Results (stdout,
// files) never depend on it.

#include <CLI/CLI.hpp>

namespace torsion::cli {

enum class Verbosity { kQuiet, kNormal, kVerbose };

/// Set once while the command line is parsed, before any subcommand runs.
Verbosity verbosity();

/// Registers --quiet and --verbose on the tool (they may also follow a subcommand).
void addVerbosityOptions(CLI::App& app);

}  // namespace torsion::cli
