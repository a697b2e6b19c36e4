#pragma once
// `torsion run SCENE.json [--out DIR] [--steps N] [--threads N]`: the headless scene runner.

#include <CLI/CLI.hpp>

#include "command_action.h"

namespace torsion::cli {

void addRunCommand(CLI::App& app, CommandAction& chosen);

}  // namespace torsion::cli
