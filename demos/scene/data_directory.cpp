#include "data_directory.h"

#include <dlfcn.h>

#include <filesystem>

namespace torsion::scene {

namespace fs = std::filesystem;

namespace {

// The file this code was loaded from: the program itself, or a shared object that carries the
// scene library (the Python module, installed under <prefix>/lib/python3/dist-packages/torsion/).
fs::path loadedObject() {
  static const char anchor = 0;  // any address inside this object will do
  Dl_info info{};
  if (dladdr(&anchor, &info) == 0 || !info.dli_fname) return {};
  std::error_code ec;
  const fs::path object = fs::canonical(info.dli_fname, ec);
  return ec ? fs::path() : object;
}

std::optional<std::string> searchUpwards(const fs::path& file, int levels) {
  std::error_code ec;
  fs::path dir = file.parent_path();
  for (int level = 0; level < levels && !dir.empty(); ++level) {
    const fs::path candidate = dir / "share" / "torsion";
    if (fs::is_directory(candidate / "demos" / "scenes", ec)) return candidate.string();
    if (dir == dir.root_path()) break;
    dir = dir.parent_path();
  }
  return std::nullopt;
}

// A wheel (`pip install`) keeps the data inside the package, beside the module:
// <site>/torsion/data.
std::optional<std::string> besideObject(const fs::path& object) {
  std::error_code ec;
  const fs::path candidate = object.parent_path() / "data";
  if (fs::is_directory(candidate / "demos" / "scenes", ec)) return candidate.string();
  return std::nullopt;
}

}  // namespace

std::optional<std::string> dataDirectory() {
  std::error_code ec;
  // A shared object first (its prefix is the package's even when the program is python3), then
  // the running program. Five levels: <prefix>/lib/python3/dist-packages/torsion/ is the deepest.
  if (const fs::path object = loadedObject(); !object.empty()) {
    if (auto found = besideObject(object)) return found;
    if (auto found = searchUpwards(object, 6)) return found;
  }
  const fs::path program = fs::read_symlink("/proc/self/exe", ec);
  if (ec || program.empty()) return std::nullopt;
  return searchUpwards(program, 4);
}

}  // namespace torsion::scene
