#include "mesh_generate_command.h"

namespace torsion::cli {

void addMeshGenerateCommands(CLI::App& /*mesh*/) {}

}  // namespace torsion::cli
