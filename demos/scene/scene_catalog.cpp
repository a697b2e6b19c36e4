#include "scene_catalog.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "data_directory.h"

namespace torsion::scene {

namespace fs = std::filesystem;

std::vector<std::string> sceneDirectories() {
  std::vector<std::string> dirs;
  if (const char* path = std::getenv("TORSION_SCENE_PATH")) {
    std::stringstream list(path);
    for (std::string dir; std::getline(list, dir, ':');)
      if (!dir.empty()) dirs.push_back(dir);
  }
  if (const std::optional<std::string> data = dataDirectory())
    dirs.push_back((fs::path(*data) / "demos" / "scenes").string());
  return dirs;
}

std::vector<std::string> sceneNames() {
  std::vector<std::string> names;
  for (const std::string& dir : sceneDirectories()) {
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
    }
  }
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

Result<std::string> resolveScene(const std::string& argument) {
  std::error_code ec;
  if (fs::is_regular_file(argument, ec)) return argument;
  const fs::path as_path(argument);
  const bool bare_name =
      !argument.empty() && !as_path.has_parent_path() && !as_path.has_extension();
  if (bare_name) {
    for (const std::string& dir : sceneDirectories()) {
      const fs::path candidate = fs::path(dir) / (argument + ".json");
      if (fs::is_regular_file(candidate, ec)) return candidate.string();
    }
  }
  std::ostringstream message;
  message << argument << ": no such scene file";
  if (bare_name) {
    message << ", and no scene of that name in";
    for (const std::string& dir : sceneDirectories())
      message << " " << dir;
    message << " (scenes:";
    for (const std::string& name : sceneNames())
      message << " " << name;
    message << ")";
  }
  return Error{message.str()};
}

}  // namespace torsion::scene
