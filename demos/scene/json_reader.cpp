#include "json_reader.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace torsion::scene {

namespace {
std::string typeName(const nlohmann::json& j) {
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_boolean()) return "a boolean";
  if (j.is_array()) return "an array";
  if (j.is_object()) return "an object";
  return "null";
}
// Within two single-character edits (insert, delete, substitute), or equal but for case.
bool spelledAlike(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  if ((n > m ? n - m : m - n) > 2) return false;
  std::vector<size_t> previous(m + 1), current(m + 1);
  for (size_t j = 0; j <= m; ++j)
    previous[j] = j;
  for (size_t i = 1; i <= n; ++i) {
    current[0] = i;
    for (size_t j = 1; j <= m; ++j) {
      const bool same = std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                        std::tolower(static_cast<unsigned char>(b[j - 1]));
      current[j] =
          std::min({previous[j] + 1, current[j - 1] + 1, previous[j - 1] + (same ? 0 : 1)});
    }
    std::swap(previous, current);
  }
  return previous[m] <= 2;
}

}  // namespace

std::string SceneFault::text() const {
  return file + ": " + (key_path.empty() ? "" : key_path + ": ") + message;
}

JsonObject::JsonObject(const nlohmann::json& json, std::string path, const std::string& file)
    : json_(json), path_(std::move(path)), file_(file) {
  if (!json_.is_object()) {
    throw JsonFault({file_, path_.empty() ? "the scene" : path_,
                     "expected an object, found " + typeName(json_)});
  }
}

std::string JsonObject::keyPath(const std::string& key) const {
  if (key.empty()) return path_;
  return path_.empty() ? key : path_ + "." + key;
}

void JsonObject::fail(const std::string& key, const std::string& fault) const {
  throw JsonFault({file_, keyPath(key), fault});
}

bool JsonObject::has(const std::string& key) const {
  read_.insert(key);
  return json_.contains(key);
}

const nlohmann::json& JsonObject::at(const std::string& key) const {
  read_.insert(key);
  if (!json_.contains(key)) {
    // A misspelt key shows up here first. Keys not read yet may well be valid ones read later,
    // so only those spelt like the missing key are offered, as a guess.
    std::string similar;
    for (auto it = json_.begin(); it != json_.end(); ++it) {
      if (read_.count(it.key()) == 0 && spelledAlike(it.key(), key))
        similar += (similar.empty() ? "" : ", ") + ("'" + it.key() + "'");
    }
    fail(key, "missing (required)" +
                  (similar.empty() ? std::string() : "; did you mean " + similar + "?"));
  }
  return json_.at(key);
}

double JsonObject::number(const std::string& key) const {
  const nlohmann::json& j = at(key);
  if (!j.is_number()) fail(key, "expected a number, found " + typeName(j));
  const double value = j.get<double>();
  if (!std::isfinite(value)) fail(key, "must be finite");
  return value;
}

double JsonObject::number(const std::string& key, double fallback) const {
  return has(key) ? number(key) : fallback;
}

int JsonObject::integer(const std::string& key, int fallback) const {
  if (!has(key)) return fallback;
  const nlohmann::json& j = at(key);
  if (!j.is_number_integer()) fail(key, "expected an integer, found " + typeName(j));
  const auto value = j.get<long long>();
  if (value < -2147483647LL || value > 2147483647LL) fail(key, "integer out of range");
  return static_cast<int>(value);
}

std::string JsonObject::string(const std::string& key) const {
  const nlohmann::json& j = at(key);
  if (!j.is_string()) fail(key, "expected a string, found " + typeName(j));
  return j.get<std::string>();
}

std::string JsonObject::string(const std::string& key, const std::string& fallback) const {
  return has(key) ? string(key) : fallback;
}

std::string nameFault(const std::string& value) {
  if (value.empty()) return "must not be empty";
  if (value.size() > 64) return "must be at most 64 characters (it names files and columns)";
  if (value == "." || value == "..") return "'" + value + "' cannot name a file";
  for (const char c : value) {
    const auto byte = static_cast<unsigned char>(c);
    const bool allowed = std::isalnum(byte) || (c != '\0' && std::strchr(" -_.+()", c) != nullptr);
    if (!allowed || byte >= 0x80) {
      char shown[8];
      if (byte >= 0x21 && byte < 0x7f) {
        std::snprintf(shown, sizeof shown, "'%c'", c);
      } else {
        std::snprintf(shown, sizeof shown, "\\x%02X", static_cast<unsigned>(byte));
      }
      return std::string("character ") + shown +
             " not allowed: names become file names and CSV columns (use letters, digits "
             "and \" -_.+()\")";
    }
  }
  return "";
}

std::string JsonObject::name(const std::string& key) const {
  const std::string value = string(key);
  if (const std::string fault = nameFault(value); !fault.empty()) fail(key, fault);
  return value;
}

bool JsonObject::boolean(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const nlohmann::json& j = at(key);
  if (!j.is_boolean()) fail(key, "expected true or false, found " + typeName(j));
  return j.get<bool>();
}

Eigen::Vector3d JsonObject::vector3(const std::string& key) const {
  const nlohmann::json& j = at(key);
  if (!j.is_array() || j.size() != 3) fail(key, "expected an array of 3 numbers");
  Eigen::Vector3d v;
  for (size_t i = 0; i < 3; ++i) {
    if (!j[i].is_number())
      fail(key, "element " + std::to_string(i) + ": expected a number, found " + typeName(j[i]));
    v[static_cast<Eigen::Index>(i)] = j[i].get<double>();
  }
  if (!v.allFinite()) fail(key, "must be finite");
  return v;
}

Eigen::Vector3d JsonObject::vector3(const std::string& key, const Eigen::Vector3d& fallback) const {
  return has(key) ? vector3(key) : fallback;
}

JsonObject JsonObject::object(const std::string& key) const {
  const nlohmann::json& j = at(key);
  if (!j.is_object()) fail(key, "expected an object, found " + typeName(j));
  return JsonObject(j, keyPath(key), file_);
}

std::vector<JsonObject> JsonObject::objects(const std::string& key) const {
  std::vector<JsonObject> out;
  if (!has(key)) return out;
  const nlohmann::json& j = at(key);
  if (!j.is_array()) fail(key, "expected an array, found " + typeName(j));
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string item = keyPath(key) + "[" + std::to_string(i) + "]";
    if (!j[i].is_object())
      throw JsonFault({file_, item, "expected an object, found " + typeName(j[i])});
    out.emplace_back(j[i], item, file_);
  }
  return out;
}

std::vector<Eigen::Vector3d> JsonObject::vector3List(const std::string& key) const {
  std::vector<Eigen::Vector3d> out;
  if (!has(key)) return out;
  const nlohmann::json& j = at(key);
  if (!j.is_array()) fail(key, "expected an array of [x, y, z], found " + typeName(j));
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string item = "element " + std::to_string(i);
    if (!j[i].is_array() || j[i].size() != 3) fail(key, item + ": expected an array of 3 numbers");
    Eigen::Vector3d v;
    for (size_t a = 0; a < 3; ++a) {
      if (!j[i][a].is_number()) fail(key, item + ": expected a number, found " + typeName(j[i][a]));
      v[static_cast<Eigen::Index>(a)] = j[i][a].get<double>();
    }
    if (!v.allFinite()) fail(key, item + ": must be finite");
    out.push_back(v);
  }
  return out;
}

std::vector<std::array<int, 3>> JsonObject::integerTriples(const std::string& key) const {
  std::vector<std::array<int, 3>> out;
  if (!has(key)) return out;
  const nlohmann::json& j = at(key);
  if (!j.is_array()) fail(key, "expected an array of [i, j, k], found " + typeName(j));
  for (size_t i = 0; i < j.size(); ++i) {
    const std::string item = "element " + std::to_string(i);
    if (!j[i].is_array() || j[i].size() != 3) fail(key, item + ": expected an array of 3 integers");
    std::array<int, 3> t{};
    for (size_t a = 0; a < 3; ++a) {
      if (!j[i][a].is_number_integer())
        fail(key, item + ": expected an integer, found " + typeName(j[i][a]));
      const auto value = j[i][a].get<long long>();
      if (value < 0 || value > 2147483647LL) fail(key, item + ": index out of range");
      t[a] = static_cast<int>(value);
    }
    out.push_back(t);
  }
  return out;
}

std::string JsonObject::oneOf(const std::vector<std::string>& choices) const {
  std::string found;
  std::string list;
  for (const std::string& c : choices) {
    list += (list.empty() ? "" : ", ") + c;
    if (has(c)) {
      if (!found.empty()) throw JsonFault({file_, path_, "give only one of " + list + "..."});
      found = c;
    }
  }
  if (found.empty()) throw JsonFault({file_, path_, "needs one of: " + list});
  return found;
}

void JsonObject::finish() const {
  for (auto it = json_.begin(); it != json_.end(); ++it) {
    if (read_.count(it.key()) == 0) {
      std::string known;
      for (const std::string& k : read_)
        known += (known.empty() ? "" : ", ") + k;
      fail(it.key(), "unknown key (known here: " + known + ")");
    }
  }
}

}  // namespace torsion::scene
