#include "text_scanner.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <system_error>

namespace torsion::detail {

namespace {
bool isSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}
}  // namespace

TextScanner::TextScanner(std::string_view text, std::string file_name, char comment)
    : text_(text), file_name_(std::move(file_name)), comment_(comment) {
  // A UTF-8 byte order mark, as some editors save it, is not part of the first line.
  if (text_.substr(0, 3) == "\xEF\xBB\xBF") pos_ = 3;
}

bool TextScanner::readRawLine() {
  if (pos_ >= text_.size()) return false;
  size_t end = text_.find('\n', pos_);
  if (end == std::string_view::npos) end = text_.size();
  std::string_view line = text_.substr(pos_, end - pos_);
  pos_ = end + 1;
  ++line_number_;
  if (comment_ != '\0') {
    size_t c = line.find(comment_);
    if (c != std::string_view::npos) line = line.substr(0, c);
  }
  size_t b = 0;
  while (b < line.size() && isSpace(line[b]))
    ++b;
  size_t e = line.size();
  while (e > b && isSpace(line[e - 1]))
    --e;
  line_text_ = line.substr(b, e - b);

  tokens_.clear();
  token_cursor_ = 0;
  size_t i = 0;
  while (i < line_text_.size()) {
    while (i < line_text_.size() && isSpace(line_text_[i]))
      ++i;
    size_t start = i;
    while (i < line_text_.size() && !isSpace(line_text_[i]))
      ++i;
    if (i > start) tokens_.push_back(line_text_.substr(start, i - start));
  }
  return true;
}

bool TextScanner::nextLine() {
  while (readRawLine()) {
    if (!tokens_.empty()) return true;
  }
  tokens_.clear();
  line_text_ = {};
  return false;
}

void TextScanner::requireLine(std::string_view what) {
  if (!nextLine()) fail("unexpected end of file, expected " + std::string(what));
}

void TextScanner::requireTokens(size_t n, std::string_view what) const {
  if (tokens_.size() < n) {
    fail("expected " + std::string(what) + " (" + std::to_string(n) + " fields), found " +
         std::to_string(tokens_.size()) + " field" + (tokens_.size() == 1 ? "" : "s"));
  }
}

std::string_view TextScanner::nextToken(std::string_view what) {
  while (token_cursor_ >= tokens_.size()) {
    if (!nextLine()) fail("unexpected end of file, expected " + std::string(what));
  }
  return tokens_[token_cursor_++];
}

bool TextScanner::atEnd() {
  while (token_cursor_ >= tokens_.size()) {
    if (!nextLine()) return true;
  }
  return false;
}

long TextScanner::parseInteger(std::string_view token, std::string_view what) const {
  long value = 0;
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (first != last && *first == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) {
    fail(std::string(what) + ": integer " + quoted(token) + " is out of range");
  }
  if (ec != std::errc() || ptr != last) {
    fail("expected an integer for " + std::string(what) + ", found " + quoted(token));
  }
  return value;
}

double TextScanner::parseReal(std::string_view token, std::string_view what) const {
  double value = 0;
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (first != last && *first == '+') ++first;
  auto [ptr, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) {
    fail(std::string(what) + ": number " + quoted(token) + " is out of range");
  }
  if (ec != std::errc() || ptr != last) {
    fail("expected a number for " + std::string(what) + ", found " + quoted(token));
  }
  if (!std::isfinite(value)) {
    fail(std::string(what) + " is not finite (" + quoted(token) + ")");
  }
  return value;
}

void TextScanner::fail(const std::string& message) const {
  failAt(line_number_, message);
}

void TextScanner::failAt(int line, const std::string& message) const {
  throw ParseFailure(file_name_ + ":" + std::to_string(line) + ": " + message);
}

size_t TextScanner::plausibleCount(long declared, size_t min_chars_per_item) const {
  if (declared <= 0) return 0;
  return std::min(static_cast<size_t>(declared), text_.size() / min_chars_per_item + 1);
}

std::string plural(long n, std::string_view one, std::string_view many) {
  return std::to_string(n) + " " + std::string(n == 1 ? one : many);
}

std::string quoted(std::string_view token) {
  constexpr size_t kMax = 40;
  std::string shown(token.substr(0, kMax));
  for (char& c : shown) {
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) c = '?';
  }
  if (token.size() > kMax) shown += "...";
  return "'" + shown + "'";
}

}  // namespace torsion::detail
