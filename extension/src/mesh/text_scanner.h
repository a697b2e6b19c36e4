#pragma once
// Reading text mesh formats with line numbers, shared by the readers (private to the library).
//
// A reader walks the text either line by line (TetGen, Gmsh) or token by token across lines
// (VTK's free-format number lists). Every failure goes through fail(), which throws ParseFailure
// with "file:line: message"; each reader's public entry point catches it and returns an Error, so
// exceptions never leave the library.

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace torsion::detail {

struct ParseFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class TextScanner {
 public:
  /// comment: a character that starts a comment running to the end of the line ('\0': none).
  TextScanner(std::string_view text, std::string file_name, char comment = '\0');

  const std::string& fileName() const { return file_name_; }
  /// The file-size guard for reserve(): the declared count of a list, but never more items than
  /// the whole text could hold at min_chars_per_item characters each (a fuzzed header may declare
  /// 10^18 of anything, and reserve() would ask for it); 0 for a count <= 0.
  size_t plausibleCount(long declared, size_t min_chars_per_item) const;

  // ---- Line by line ----
  /// Moves to the next line that has a token; false at end of text. Splits it into tokens().
  bool nextLine();
  /// Like nextLine() but fails with "unexpected end of file, expected <what>" at the end.
  void requireLine(std::string_view what);
  /// Tokens of the current line (views into the text; valid while the scanner lives).
  const std::vector<std::string_view>& tokens() const { return tokens_; }
  /// The current line, comment removed and whitespace trimmed.
  std::string_view lineText() const { return line_text_; }
  /// 1-based number of the current line (or of the last token read).
  int lineNumber() const { return line_number_; }
  /// Fails unless the current line has at least n tokens.
  void requireTokens(size_t n, std::string_view what) const;

  // ---- Token by token (crosses lines) ----
  /// Next token after the ones already consumed on the current line; moves on to following lines
  /// as needed. Fails with "unexpected end of file, expected <what>" at the end.
  std::string_view nextToken(std::string_view what);
  /// True when no token is left in the text.
  bool atEnd();

  // ---- Numbers ----
  long parseInteger(std::string_view token, std::string_view what) const;
  double parseReal(std::string_view token, std::string_view what) const;  ///< finite only
  long nextInteger(std::string_view what) { return parseInteger(nextToken(what), what); }

  /// Throws ParseFailure("file:line: message") at the current line.
  [[noreturn]] void fail(const std::string& message) const;
  /// Throws ParseFailure("file:line: message") at the given line.
  [[noreturn]] void failAt(int line, const std::string& message) const;

 private:
  bool readRawLine();  // advances pos_ over one physical line; false at end

  std::string_view text_;
  std::string file_name_;
  char comment_;
  size_t pos_ = 0;
  int line_number_ = 0;
  std::string_view line_text_;
  std::vector<std::string_view> tokens_;
  size_t token_cursor_ = 0;  // tokens of the current line already consumed by nextToken()
};

/// Quotes a token for an error message, shortened if long.
std::string quoted(std::string_view token);

/// "1 node", "3 nodes": a count with its noun for an error message.
std::string plural(long n, std::string_view one, std::string_view many);

}  // namespace torsion::detail
