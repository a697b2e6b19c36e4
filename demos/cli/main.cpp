// torsion: the command-line tool. Each subcommand lives in its own file and registers itself here.

#include <CLI/CLI.hpp>
#include <iostream>

#include "mesh_command.h"
#include "run_command.h"
#include "view_command.h"

int main(int argc, char** argv) {
  CLI::App app{"torsion: corotational FEM soft bodies with hand-plane torsion, inside Bullet"};
  app.require_subcommand(1);
  torsion::cli::addMeshCommand(app);
  torsion::cli::addRunCommand(app);
  torsion::cli::addViewCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  return torsion::cli::exitCode();
}
