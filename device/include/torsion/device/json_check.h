#pragma once
// A strict first pass over JSON text, before a parser builds the document. nlohmann's parser keeps
// the last of two equal keys in an object and throws out_of_range (not parse_error) on a number a
// double cannot hold (1e400); this pass turns both, and every syntax error, into one message with
// a line and column, so loaders report them instead of losing a key or aborting.

#include <optional>
#include <string>
#include <string_view>

namespace torsion::device {

/// What is wrong with a JSON text, and where when the parser knows (syntax errors and numbers;
/// a duplicate key is named by its path instead).
struct JsonTextFault {
  int line = 0;    ///< 1-based; 0 when the position is unknown
  int column = 0;  ///< 1-based, in bytes
  /// e.g. "duplicate key 'steps' in the top-level object",
  ///      "number out of range of a double: 1e400", "syntax error while parsing value - ...".
  /// Bytes that are not printable ASCII are shown as \xHH, never echoed raw.
  std::string what;
};

/// The deepest nesting of arrays and objects a JSON text may have. Code that walks a document
/// recurses once per level (and so does nlohmann's copy, comparison and dump): a bound keeps a
/// hostile or broken file from overflowing the stack. Project files nest a few levels.
inline constexpr int kMaxJsonDepth = 64;

/// Nothing when the text is one well-formed JSON value with no duplicate key in any object, no
/// number outside a double's range and no nesting deeper than kMaxJsonDepth; otherwise the first
/// fault ("nested deeper than 64 levels", at the bracket that opens level 65).
std::optional<JsonTextFault> findJsonTextFault(std::string_view text);

/// The text made safe for a one-line message: printable ASCII kept, other bytes as \xHH,
/// cut to max_chars with "..." when longer.
std::string printableExcerpt(std::string_view text, size_t max_chars = 80);

}  // namespace torsion::device
