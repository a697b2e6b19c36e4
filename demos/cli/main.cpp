// torsion: the command-line tool. Each subcommand lives in its own file and registers itself here.

#include <LinearMath/btScalar.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <iostream>

#include "../scene/build_info.h"
#include "check_command.h"
#include "mesh_command.h"
#include "run_command.h"
#include "text_only_stderr.h"
#include "torsion/device/file_io.h"
#include "torsion/device/json_check.h"
#include "torsion/solve/parallel.h"
#include "verbosity.h"
#include "view_command.h"

int main(int argc, char** argv) {
  const torsion::cli::TextOnlyStderr text_only_stderr;  // no raw bytes from user input on stderr
  CLI::App app{"torsion: corotational FEM soft bodies with hand-plane torsion, inside Bullet"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("torsion ") + torsion::scene::torsionVersion() +
                                        " (git " + torsion::scene::torsionGitCommit() + ", " +
                                        (sizeof(btScalar) == 8 ? "double" : "float") + " Bullet)");
  app.fallthrough();  // options of the tool (--max-input-mb) may follow a subcommand
  app.add_option_function<double>(
         "--max-input-mb",
         [](double mb) {
           torsion::device::setMaxInputFileBytes(static_cast<std::size_t>(std::llround(mb * 1e6)));
         },
         "Largest scene, mesh or trajectory file read, in MB (default 1073.741824, i.e. 1 GiB)")
      ->check(CLI::Range(1e-6, 1e9))
      ->trigger_on_parse();  // before the subcommand's callback reads anything
  torsion::cli::addVerbosityOptions(app);
  torsion::cli::CommandAction chosen;  // set by the subcommand the command line names
  torsion::cli::addMeshCommand(app, chosen);
  torsion::cli::addRunCommand(app, chosen);
  torsion::cli::addViewCommand(app, chosen);
  torsion::cli::addCheckCommand(app, chosen);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    // Usage errors exit 1 like every other error, on one "error:" line (CLI11 uses 104-114).
    std::cerr << "error: " << e.what() << "\nrun '" << argv[0]
              << " --help' (or '<command> --help') for usage\n";
    return 1;
  }
  // The library ignores a malformed TORSION_THREADS (it has no one to tell); the tool says so.
  if (const char* threads = std::getenv(torsion::kThreadsVariable);
      threads != nullptr && *threads != '\0' && !torsion::threadsFromEnvironment()) {
    std::cerr << "error: " << torsion::kThreadsVariable << "='"
              << torsion::device::printableExcerpt(threads)
              << "' is not a whole number of threads from 1 to " << torsion::kMaxThreads
              << " (unset it to use every core)\n";
    return 1;
  }
  return chosen ? chosen() : 0;
}
