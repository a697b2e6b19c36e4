#include "torsion/device/json_check.h"

#include <cstdio>
#include <nlohmann/json.hpp>
#include <set>
#include <vector>

namespace torsion::device {

namespace {

using json = nlohmann::json;

// Line and column (1-based, columns in bytes) of a byte offset.
void locate(std::string_view text, size_t offset, JsonTextFault& fault) {
  offset = std::min(offset, text.size());
  int line = 1;
  size_t line_start = 0;
  for (size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  fault.line = line;
  fault.column = static_cast<int>(offset - line_start + 1);
}

// The offset of the bracket that opens nesting level `level` (1 = the outermost), skipping
// strings; the text is well-formed up to there (the parser got that far).
size_t openingOfLevel(std::string_view text, size_t level) {
  size_t depth = 0;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth == level) return i;
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return text.size();
}

// A SAX consumer that builds nothing: it keeps, per open object, the keys seen so far and the
// path to it, and stops at the first fault.
class StrictChecker {
 public:
  explicit StrictChecker(std::string_view text) : text_(text) {}

  const std::optional<JsonTextFault>& fault() const { return fault_; }

  bool null() { return value(); }
  bool boolean(bool) { return value(); }
  bool number_integer(json::number_integer_t) { return value(); }
  bool number_unsigned(json::number_unsigned_t) { return value(); }
  bool number_float(json::number_float_t, const json::string_t&) { return value(); }
  bool string(json::string_t&) { return value(); }
  bool binary(json::binary_t&) { return value(); }

  bool start_object(std::size_t) { return open(true); }
  bool key(json::string_t& k) {
    Level& level = levels_.back();
    if (!level.keys.insert(k).second) {
      fault_ = JsonTextFault{};
      fault_->what = "duplicate key '" + printableExcerpt(k) + "' in " +
                     (levels_.size() == 1 ? std::string("the top-level object")
                                          : "object '" + pathTo(levels_.size() - 1) + "'");
      return false;  // stops the parse; position() is not known for a key, the path is
    }
    level.key = k;
    return true;
  }
  bool end_object() {
    close();
    return true;
  }
  bool start_array(std::size_t) { return open(false); }
  bool end_array() {
    close();
    return true;
  }

  bool parse_error(std::size_t position, const std::string& token,
                   const nlohmann::detail::exception& e) {
    std::string what;
    if (e.id == 406) {
      what = "number out of range of a double: " + printableExcerpt(token);
    } else {
      // nlohmann's text repeats the position ("... at line 2, column 3: "); keep the fault only.
      what = e.what();
      const size_t column = what.find("column ");
      const size_t colon =
          column == std::string::npos ? std::string::npos : what.find(": ", column);
      if (colon != std::string::npos) what = what.substr(colon + 2);
      what = printableExcerpt(what, 200);
    }
    fault_ = JsonTextFault{};
    // A number is located at its first character; a syntax error where the parser stopped.
    const size_t at = e.id == 406 && position >= token.size() ? position - token.size()
                                                              : (position == 0 ? 0 : position - 1);
    locate(text_, at, *fault_);
    fault_->what = what;
    return false;
  }

 private:
  struct Level {
    bool is_object = false;
    std::set<std::string> keys;
    std::string key;   // the last key of an object
    size_t index = 0;  // the next element of an array
  };

  // Counts a value in its enclosing array.
  bool value() {
    if (!levels_.empty() && !levels_.back().is_object) ++levels_.back().index;
    return true;
  }
  // False (the parse stops) when the new level is one too deep.
  bool open(bool is_object) {
    if (levels_.size() >= static_cast<size_t>(kMaxJsonDepth)) {
      fault_ = JsonTextFault{};
      locate(text_, openingOfLevel(text_, levels_.size() + 1), *fault_);
      fault_->what = "nested deeper than " + std::to_string(kMaxJsonDepth) + " levels";
      return false;
    }
    levels_.emplace_back();
    levels_.back().is_object = is_object;
    return true;
  }
  void close() {
    levels_.pop_back();
    value();
  }
  // The path of the container at levels_[depth] ("bodies[0].material").
  std::string pathTo(size_t depth) const {
    std::string path;
    for (size_t i = 0; i < depth; ++i) {
      const Level& parent = levels_[i];
      if (parent.is_object) {
        path += (path.empty() ? "" : ".") + printableExcerpt(parent.key);
      } else {
        path += "[" + std::to_string(parent.index) + "]";
      }
    }
    return path;
  }

  std::string_view text_;
  std::vector<Level> levels_;
  std::optional<JsonTextFault> fault_;
};

}  // namespace

std::string printableExcerpt(std::string_view text, size_t max_chars) {
  std::string out;
  for (const char c : text) {
    if (out.size() >= max_chars) {
      out += "...";
      break;
    }
    const auto byte = static_cast<unsigned char>(c);
    if (byte >= 0x20 && byte < 0x7f) {
      out += c;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02X", byte);
      out += hex;
    }
  }
  return out;
}

std::optional<JsonTextFault> findJsonTextFault(std::string_view text) {
  StrictChecker checker(text);
  if (json::sax_parse(text.begin(), text.end(), &checker)) return std::nullopt;
  if (checker.fault()) return checker.fault();
  return JsonTextFault{0, 0, "not valid JSON"};
}

}  // namespace torsion::device
