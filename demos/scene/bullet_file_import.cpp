#include "bullet_file_import.h"

#include <filesystem>
#include <system_error>

#include "bullet_file_reader.h"
#include "isolated_call.h"

namespace torsion::scene {

Result<nlohmann::json> importBulletFile(const std::string& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    return Error{path + ": " + (error ? error.message() : "no such file")};
  Result<std::string> text =
      runIsolated([&path] { return bulletFileBodiesJson(path); }, "Bullet's .bullet reader");
  if (!text) return Error{path + ": " + text.error().message};
  nlohmann::json bodies = nlohmann::json::parse(text.value(), nullptr, /*allow_exceptions=*/false);
  if (bodies.is_discarded() || !bodies.is_object())
    return Error{path + ": Bullet's .bullet reader answered in a form it never writes"};
  return bodies;
}

}  // namespace torsion::scene
