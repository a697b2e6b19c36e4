#include "data_directory.h"

#include <filesystem>

namespace torsion::scene {

namespace fs = std::filesystem;

std::optional<std::string> dataDirectory() {
  std::error_code ec;
  const fs::path program = fs::read_symlink("/proc/self/exe", ec);
  if (ec || program.empty()) return std::nullopt;
  fs::path dir = program.parent_path();
  for (int level = 0; level < 4 && !dir.empty(); ++level) {
    const fs::path candidate = dir / "share" / "torsion";
    if (fs::is_directory(candidate / "demos" / "scenes", ec)) return candidate.string();
    if (dir == dir.root_path()) break;
    dir = dir.parent_path();
  }
  return std::nullopt;
}

}  // namespace torsion::scene
