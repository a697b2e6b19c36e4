#pragma once
// `torsion view SCENE`: the scene in a GLFW window (see docs/rendering.md for the controls).

#include <CLI/CLI.hpp>

#include "command_action.h"

namespace torsion::cli {

void addViewCommand(CLI::App& app, CommandAction& chosen);

}  // namespace torsion::cli
