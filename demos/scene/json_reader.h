#pragma once
// Typed, path-tracking access to a JSON object for scene files. Each accessor fails with a
// SceneFault (thrown as JsonFault, caught by parseScene), and finish() rejects any key that was
// never asked for, so a misspelt key never passes silently.

#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace torsion::scene {

/// A fault in a scene file: the file, where in it (the key path, "bodies[0].material.density";
/// empty for the scene as a whole) and what is wrong. Formatted once, by text():
/// "<file>: <key path>: <message>" ("<file>: <message>" without a key path).
struct SceneFault {
  std::string file;
  std::string key_path;
  std::string message;

  std::string text() const;
};

/// Thrown by JsonObject and the readers built on it; parseScene returns fault.text() as its Error.
struct JsonFault : std::runtime_error {
  explicit JsonFault(SceneFault f) : std::runtime_error(f.text()), fault(std::move(f)) {}
  SceneFault fault;
};

/// What is wrong with `value` as a name of a scene's part (JsonObject::name's rule), or "" when
/// it is a valid name. Also applied to the names parts are given in code (the Python module).
std::string nameFault(const std::string& value);

class JsonObject {
 public:
  JsonObject(const nlohmann::json& json, std::string path, const std::string& file);

  bool has(const std::string& key) const;
  double number(const std::string& key) const;
  double number(const std::string& key, double fallback) const;
  int integer(const std::string& key, int fallback) const;
  std::string string(const std::string& key) const;
  std::string string(const std::string& key, const std::string& fallback) const;
  /// A name that becomes part of a file name or a CSV column (<body>.vtk, "<set>.fx"): not
  /// empty, at most 64 bytes, printable ASCII letters, digits and " -_.+()" only, not "." or
  /// "..", so it can neither leave --out nor break a CSV header.
  std::string name(const std::string& key) const;
  bool boolean(const std::string& key, bool fallback) const;
  Eigen::Vector3d vector3(const std::string& key) const;
  Eigen::Vector3d vector3(const std::string& key, const Eigen::Vector3d& fallback) const;
  JsonObject object(const std::string& key) const;
  std::vector<JsonObject> objects(
      const std::string& key) const;  ///< an array of objects; [] if absent
  /// An array of 3-vectors, e.g. points: [[x, y, z], ...]; [] if absent.
  std::vector<Eigen::Vector3d> vector3List(const std::string& key) const;
  /// An array of integer triples, e.g. triangles: [[i, j, k], ...]; [] if absent.
  std::vector<std::array<int, 3>> integerTriples(const std::string& key) const;
  /// The single key present among `choices` (exactly one must be).
  std::string oneOf(const std::vector<std::string>& choices) const;

  /// Fails on keys never read through this object.
  void finish() const;

  /// Throws the fault at this object's key (an empty key: at the object itself).
  [[noreturn]] void fail(const std::string& key, const std::string& fault) const;
  const std::string& path() const { return path_; }

 private:
  const nlohmann::json& at(const std::string& key) const;
  std::string keyPath(const std::string& key) const;

  const nlohmann::json& json_;
  std::string path_;
  const std::string& file_;
  mutable std::set<std::string> read_;
};

}  // namespace torsion::scene
