#pragma once
// Line-by-line reading of the text surface formats (.off, .obj, ASCII .stl), with line numbers
// for error messages. Private to demos/meshgen: every failure throws SurfaceParseError with
// "file:line: message", and each reader's entry point turns it into an Error.

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace torsion::meshgen::detail {

struct SurfaceParseError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A token for an error message: quoted, shortened if long.
inline std::string quoted(std::string_view token) {
  if (token.size() > 40) return "'" + std::string(token.substr(0, 37)) + "...'";
  return "'" + std::string(token) + "'";
}

class LineCursor {
 public:
  /// comment: a character starting a comment that runs to the end of the line ('\0': none).
  LineCursor(std::string_view text, std::string file, char comment)
      : text_(text), file_(std::move(file)), comment_(comment) {}

  /// Moves to the next line holding a token; false at the end of the text.
  bool next() {
    while (pos_ < text_.size()) {
      const size_t end = text_.find('\n', pos_);
      std::string_view line =
          text_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
      pos_ = end == std::string_view::npos ? text_.size() : end + 1;
      ++line_;
      if (comment_ != '\0') {
        const size_t c = line.find(comment_);
        if (c != std::string_view::npos) line = line.substr(0, c);
      }
      split(line);
      if (!tokens_.empty()) return true;
    }
    tokens_.clear();
    return false;
  }

  /// Like next(), but fails with "unexpected end of file, expected <what>" at the end.
  void require(std::string_view what) {
    if (!next()) {
      failAt(line_ > 0 ? line_ : 1, "unexpected end of file, expected " + std::string(what));
    }
  }

  const std::vector<std::string_view>& tokens() const { return tokens_; }
  int line() const { return line_; }
  const std::string& file() const { return file_; }

  [[noreturn]] void fail(const std::string& message) const { failAt(line_, message); }
  [[noreturn]] void failAt(int line, const std::string& message) const {
    throw SurfaceParseError(file_ + ":" + std::to_string(line) + ": " + message);
  }

  double real(std::string_view token, std::string_view what) const {
    double value = 0;
    const char* first = token.data();
    const char* last = token.data() + token.size();
    if (first != last && *first == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last) {
      fail("expected a number for " + std::string(what) + ", got " + quoted(token));
    }
    if (!std::isfinite(value)) fail(std::string(what) + " is not finite: " + quoted(token));
    return value;
  }

  long integer(std::string_view token, std::string_view what) const {
    long value = 0;
    const char* first = token.data();
    const char* last = token.data() + token.size();
    if (first != last && *first == '+') ++first;
    const auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr != last) {
      fail("expected an integer for " + std::string(what) + ", got " + quoted(token));
    }
    return value;
  }

 private:
  void split(std::string_view line) {
    tokens_.clear();
    size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && isSpace(line[i]))
        ++i;
      const size_t start = i;
      while (i < line.size() && !isSpace(line[i]))
        ++i;
      if (i > start) tokens_.push_back(line.substr(start, i - start));
    }
  }
  static bool isSpace(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
  }

  std::string_view text_;
  std::string file_;
  char comment_;
  size_t pos_ = 0;
  int line_ = 0;
  std::vector<std::string_view> tokens_;
};

}  // namespace torsion::meshgen::detail
