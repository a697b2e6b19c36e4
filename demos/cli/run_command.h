#pragma once
// `torsion run SCENE.json [--out DIR] [--steps N] [--threads N]`: the headless scene runner.

#include <CLI/CLI.hpp>

namespace torsion::cli {

void addRunCommand(CLI::App& app);

}  // namespace torsion::cli
