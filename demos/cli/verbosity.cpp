#include "verbosity.h"

namespace torsion::cli {

namespace {
Verbosity g_verbosity = Verbosity::kNormal;
}  // namespace

Verbosity verbosity() {
  return g_verbosity;
}

void addVerbosityOptions(CLI::App& app) {
  CLI::Option* quiet = app.add_flag_callback(
      "-q,--quiet", [] { g_verbosity = Verbosity::kQuiet; },
      "Print only warnings and errors on stderr (no progress)");
  CLI::Option* verbose = app.add_flag_callback(
      "--verbose", [] { g_verbosity = Verbosity::kVerbose; },
      "Also print the settings resolved (scene file, threads, solver)");
  quiet->excludes(verbose);
  quiet->trigger_on_parse();  // before the subcommand's callback prints anything
  verbose->trigger_on_parse();
}

}  // namespace torsion::cli
