#pragma once
// `--device NAME=TYPE[:ARG]` (repeatable) and `--haptics MODE`: one definition for the commands
// that step a scene (`torsion run`, `torsion view`); scene::applyDeviceOverrides applies them.

#include <CLI/CLI.hpp>

#include "device_parser.h"

namespace torsion::cli {

void addDeviceOptions(CLI::App& command, scene::DeviceOverrides& into);

}  // namespace torsion::cli
