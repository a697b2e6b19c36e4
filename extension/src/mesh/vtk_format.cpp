#include "torsion/mesh/vtk_format.h"

#include <algorithm>
#include <cassert>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdio>
#include <initializer_list>
#include <map>
#include <string>
#include <system_error>
#include <vector>

#include "text_scanner.h"

namespace torsion {

namespace {

using detail::plural;
using detail::quoted;
using detail::TextScanner;

constexpr long kTetraType = 10;

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    const char x = a[i], y = b[i];
    const char lx = (x >= 'A' && x <= 'Z') ? static_cast<char>(x - 'A' + 'a') : x;
    const char ly = (y >= 'A' && y <= 'Z') ? static_cast<char>(y - 'A' + 'a') : y;
    if (lx != ly) return false;
  }
  return true;
}

bool isOneOf(std::string_view token, std::initializer_list<std::string_view> words) {
  return std::any_of(words.begin(), words.end(),
                     [&](std::string_view w) { return iequals(token, w); });
}

// Words that start a section (or an array inside CELLS). One of them where a counted list expects
// a value means the list is shorter than its header declares. VTK reads keywords
// case-insensitively.
bool isKeyword(std::string_view token) {
  return isOneOf(token, {"POINTS", "CELLS", "CELL_TYPES", "OFFSETS", "CONNECTIVITY", "POINT_DATA",
                         "CELL_DATA", "FIELD", "METADATA", "DATASET"});
}

bool isIntegerType(std::string_view type) {
  return isOneOf(type, {"char", "signed_char", "unsigned_char", "short", "unsigned_short", "int",
                        "unsigned_int", "long", "unsigned_long", "vtkIdType", "vtktypeint8",
                        "vtktypeuint8", "vtktypeint16", "vtktypeuint16", "vtktypeint32",
                        "vtktypeuint32", "vtktypeint64", "vtktypeuint64"});
}

bool isNumericType(std::string_view type) {
  return isIntegerType(type) || isOneOf(type, {"float", "double"});
}

bool looksNumeric(std::string_view token) {
  const char c = token.front();
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

const char* cellTypeName(long type) {
  static const std::map<long, const char*> kNames = {{0, "empty cell"},
                                                     {1, "vertex"},
                                                     {2, "poly-vertex"},
                                                     {3, "line"},
                                                     {4, "poly-line"},
                                                     {5, "triangle"},
                                                     {6, "triangle strip"},
                                                     {7, "polygon"},
                                                     {8, "pixel"},
                                                     {9, "quad"},
                                                     {10, "tetrahedron"},
                                                     {11, "voxel"},
                                                     {12, "hexahedron"},
                                                     {13, "wedge"},
                                                     {14, "pyramid"},
                                                     {15, "pentagonal prism"},
                                                     {16, "hexagonal prism"},
                                                     {21, "quadratic edge"},
                                                     {22, "quadratic triangle"},
                                                     {23, "quadratic quad"},
                                                     {24, "quadratic tetrahedron"},
                                                     {25, "quadratic hexahedron"},
                                                     {26, "quadratic wedge"},
                                                     {27, "quadratic pyramid"},
                                                     {28, "biquadratic quad"},
                                                     {29, "triquadratic hexahedron"},
                                                     {34, "biquadratic triangle"},
                                                     {35, "cubic line"},
                                                     {42, "polyhedron"},
                                                     {68, "Lagrange triangle"},
                                                     {71, "Lagrange tetrahedron"},
                                                     {72, "Lagrange hexahedron"}};
  const auto found = kNames.find(type);
  return found == kNames.end() ? "unknown cell type" : found->second;
}

// "what is declared" for a counted list, e.g. "POINTS (line 5) declares 900 points"; the reader
// appends ", found N" when the data runs out early.
struct List {
  std::string declares;
};

class VtkReader {
 public:
  VtkReader(std::string_view text, std::string_view file) : in_(text, std::string(file)) {}

  RawTetMesh read();

 private:
  // ---- tokens, with one token of push-back ----
  std::string_view next(std::string_view what) {
    if (has_pending_) {
      has_pending_ = false;
      return pending_;
    }
    return in_.nextToken(what);
  }
  void putBack(std::string_view token) {
    pending_ = token;
    has_pending_ = true;
  }
  bool atEnd() { return !has_pending_ && in_.atEnd(); }
  long nextInteger(std::string_view what) { return in_.parseInteger(next(what), what); }

  /// The next value of a counted list; the end of the file or a keyword in its place means the
  /// list is shorter than its header declares.
  std::string_view listToken(const List& list, long found) {
    if (atEnd()) {
      in_.fail("unexpected end of file: " + list.declares + ", found " + std::to_string(found));
    }
    const std::string_view token = next("a value");
    if (isKeyword(token)) {
      in_.fail(list.declares + ", found " + std::to_string(found) + " before " + quoted(token));
    }
    return token;
  }
  // Fast paths; the scanner's parsers (which build the message) only run on unusual tokens.
  template <class What>
  double realToken(std::string_view token, What&& what) const {
    double value = 0;
    const char* last = token.data() + token.size();
    auto [ptr, ec] = std::from_chars(token.data(), last, value);
    if (ec == std::errc() && ptr == last && std::isfinite(value)) return value;
    return in_.parseReal(token, what());
  }
  template <class What>
  long integerToken(std::string_view token, What&& what) const {
    long value = 0;
    const char* last = token.data() + token.size();
    auto [ptr, ec] = std::from_chars(token.data(), last, value);
    if (ec == std::errc() && ptr == last) return value;
    return in_.parseInteger(token, what());
  }

  std::string atLine(int line) const { return "(line " + std::to_string(line) + ")"; }
  void refuseSecond(int first_line, const char* section) const {
    if (first_line > 0) {
      in_.fail(std::string("a second ") + section + " section; the first is at line " +
               std::to_string(first_line));
    }
  }

  void readHeader();
  void readPoints();
  void readCells();
  void readClassicCells(long count, long size);
  void readOffsetCells(long offset_count, long size);
  int checkedPoint(long point, long cell) const;
  void readCellTypes();
  void skipField();
  void skipToKeyword();

  TextScanner in_;
  std::string_view pending_;
  bool has_pending_ = false;

  int points_line_ = 0;  // line of each section's keyword; 0: not read yet
  int cells_line_ = 0;
  int types_line_ = 0;
  const char* last_section_ = "DATASET";
  int last_section_line_ = 0;

  std::vector<Eigen::Vector3d> positions_;
  std::vector<size_t> cell_begin_{0};  // cell c's points: connectivity_[begin[c] .. begin[c+1])
  std::vector<int> connectivity_;
  std::vector<int> cell_lines_;  // where each cell's row (or its connectivity) starts
  RawTetMesh raw_;
};

void VtkReader::readHeader() {
  const std::string header = "the header '# vtk DataFile Version X.Y'";
  in_.requireLine(header);
  const std::vector<std::string_view>& t = in_.tokens();
  if (t.size() < 4 || t[0] != "#" || !iequals(t[1], "vtk") || !iequals(t[2], "DataFile") ||
      !iequals(t[3], "Version")) {
    in_.fail("expected " + header + ", found " + quoted(in_.lineText()) +
             "; not a legacy VTK file");
  }
  const std::string_view version = t.size() > 4 ? t[4] : std::string_view();
  const size_t dot = version.find('.');
  const auto digits = [](std::string_view s) {
    return !s.empty() && s.size() < 6 &&
           std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
  };
  if (dot == std::string_view::npos || !digits(version.substr(0, dot)) ||
      !digits(version.substr(dot + 1))) {
    in_.fail("garbled header: expected a version X.Y after 'Version', found " +
             (version.empty() ? std::string("nothing") : quoted(version)));
  }
  const int header_line = in_.lineNumber();

  // The title is the next line, whatever it holds (it may be blank, which nextLine() skips).
  in_.requireLine("the title line");
  if (in_.lineNumber() == header_line + 1) in_.requireLine("'ASCII' or 'BINARY'");
  const std::string_view format = next("'ASCII' or 'BINARY'");
  if (iequals(format, "BINARY")) {
    in_.fail("BINARY legacy VTK files are not supported; save the mesh as ASCII");
  }
  if (!iequals(format, "ASCII")) {
    in_.fail("expected 'ASCII' or 'BINARY' after the title line, found " + quoted(format) +
             (iequals(format, "DATASET") ? " (is the title line missing?)" : ""));
  }

  const std::string_view dataset = next("'DATASET UNSTRUCTURED_GRID'");
  if (!iequals(dataset, "DATASET")) {
    in_.fail("expected 'DATASET UNSTRUCTURED_GRID', found " + quoted(dataset));
  }
  const std::string_view type = next("the dataset type after DATASET");
  if (!iequals(type, "UNSTRUCTURED_GRID")) {
    in_.fail("dataset " + quoted(type) +
             " is not supported; only UNSTRUCTURED_GRID holds a tetrahedral mesh");
  }
  last_section_line_ = in_.lineNumber();
}

void VtkReader::readPoints() {
  const int line = in_.lineNumber();
  refuseSecond(points_line_, "POINTS");
  points_line_ = line;
  const long count = nextInteger("the number of points");
  const std::string_view type = next("the POINTS data type");
  if (count <= 0) {
    in_.fail("POINTS declares " + std::to_string(count) + " points; a mesh needs some");
  }
  if (count > INT_MAX) {
    in_.fail("POINTS declares " + std::to_string(count) + " points; at most " +
             std::to_string(INT_MAX) + " are supported");
  }
  if (!isNumericType(type)) {
    in_.fail("POINTS data type " + quoted(type) + " is not a numeric type (float, double, int...)");
  }
  const List list{"POINTS " + atLine(line) + " declares " + plural(count, "point", "points")};
  positions_.reserve(in_.plausibleCount(count, 6));  // "0 0 0\n"
  for (long i = 0; i < count; ++i) {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) {
      p[d] = realToken(listToken(list, i), [&] {
        return std::string("coordinate ") + "xyz"[d] + " of point " + std::to_string(i);
      });
    }
    positions_.push_back(p);
  }
  last_section_ = "POINTS";
  last_section_line_ = line;
}

int VtkReader::checkedPoint(long point, long cell) const {
  const long count = static_cast<long>(positions_.size());
  if (point < 0 || point >= count) {
    in_.fail("cell " + std::to_string(cell) + ": point " + std::to_string(point) +
             (point < 0 ? " is negative" : " >= point count " + std::to_string(count)));
  }
  return static_cast<int>(point);
}

void VtkReader::readCells() {
  const int line = in_.lineNumber();
  refuseSecond(cells_line_, "CELLS");
  if (points_line_ == 0) in_.fail("CELLS before POINTS; the points must come first");
  cells_line_ = line;
  const long count = nextInteger("the number of cells");
  const long size = nextInteger("the size of the cell list");
  if (count < 0 || size < 0) {
    in_.fail("CELLS declares negative sizes (" + std::to_string(count) + " " +
             std::to_string(size) + ")");
  }
  if (count == 0) in_.fail("CELLS declares no cells; a mesh needs tetrahedra (cell type 10)");
  // Version 5.1 follows the header with OFFSETS and CONNECTIVITY arrays; older versions with rows.
  const std::string_view first = next("the cells that CELLS " + atLine(line) + " declares");
  if (iequals(first, "OFFSETS")) {
    readOffsetCells(count, size);
  } else {
    putBack(first);
    readClassicCells(count, size);
  }
  if (cell_lines_.empty()) {
    in_.failAt(line, "CELLS holds no cells; a mesh needs tetrahedra (cell type 10)");
  }
  last_section_ = "CELLS";
  last_section_line_ = line;
}

// "CELLS n size", then n rows "k i0 .. ik-1" with size == sum of (k + 1).
void VtkReader::readClassicCells(long count, long size) {
  const List list{"CELLS " + atLine(cells_line_) + " declares " + plural(count, "cell", "cells")};
  cell_begin_.reserve(in_.plausibleCount(count, 2) + 1);
  cell_lines_.reserve(in_.plausibleCount(count, 2));
  connectivity_.reserve(in_.plausibleCount(size, 2));
  long used = 0;
  for (long c = 0; c < count; ++c) {
    const long k = integerToken(listToken(list, c),
                                [&] { return "the point count of cell " + std::to_string(c); });
    const int row_line = in_.lineNumber();
    if (k < 0)
      in_.fail("cell " + std::to_string(c) + ": negative point count " + std::to_string(k));
    if (k > size - used - 1) {
      in_.fail("cell " + std::to_string(c) + ": its " + plural(k, "point runs", "points run") +
               " past the list size " + std::to_string(size) + " that CELLS " +
               atLine(cells_line_) + " declares");
    }
    used += k + 1;
    for (long j = 0; j < k; ++j) {
      const long point = integerToken(listToken(list, c), [&] {
        return "point " + std::to_string(j) + " of cell " + std::to_string(c);
      });
      connectivity_.push_back(checkedPoint(point, c));
    }
    cell_begin_.push_back(connectivity_.size());
    cell_lines_.push_back(row_line);
  }
  if (used != size) {
    in_.failAt(cells_line_, "CELLS declares a list size of " + std::to_string(size) + ", but its " +
                                plural(count, "cell uses", "cells use") + " " +
                                std::to_string(used) + " (each cell counts its points + 1)");
  }
}

// "CELLS <cells + 1> <size>", "OFFSETS <type>" + cells + 1 offsets, "CONNECTIVITY <type>" + size
// point indices (VTK 5.1).
void VtkReader::readOffsetCells(long offset_count, long size) {
  const std::string_view offsets_type = next("the OFFSETS data type");
  if (!isIntegerType(offsets_type)) {
    in_.fail("OFFSETS data type " + quoted(offsets_type) + " is not an integer type");
  }
  const List offsets{"CELLS " + atLine(cells_line_) + " declares " +
                     plural(offset_count, "offset", "offsets")};
  cell_begin_.clear();
  cell_begin_.reserve(in_.plausibleCount(offset_count, 2));
  long previous = 0;
  for (long i = 0; i < offset_count; ++i) {
    const long offset =
        integerToken(listToken(offsets, i), [&] { return "offset " + std::to_string(i); });
    if (i == 0 && offset != 0)
      in_.fail("the first offset must be 0, found " + std::to_string(offset));
    if (offset < previous) {
      in_.fail("offset " + std::to_string(i) + " (" + std::to_string(offset) +
               ") is smaller than the one before it (" + std::to_string(previous) + ")");
    }
    if (offset > size) {
      in_.fail("offset " + std::to_string(i) + " (" + std::to_string(offset) +
               ") is beyond the connectivity size " + std::to_string(size) + " that CELLS " +
               atLine(cells_line_) + " declares");
    }
    cell_begin_.push_back(static_cast<size_t>(offset));
    previous = offset;
  }
  if (previous != size) {
    in_.fail("the last offset is " + std::to_string(previous) + ", but CELLS " +
             atLine(cells_line_) + " declares " + std::to_string(size) + " connectivity entries");
  }

  std::string_view word = next("CONNECTIVITY");
  if (iequals(word, "METADATA")) {
    skipToKeyword();
    word = next("CONNECTIVITY");
  }
  if (!iequals(word, "CONNECTIVITY")) {
    in_.fail("expected CONNECTIVITY after the " + plural(offset_count, "offset", "offsets") +
             " that CELLS " + atLine(cells_line_) + " declares, found " + quoted(word));
  }
  const std::string_view type = next("the CONNECTIVITY data type");
  if (!isIntegerType(type)) {
    in_.fail("CONNECTIVITY data type " + quoted(type) + " is not an integer type");
  }
  const List entries{"CELLS " + atLine(cells_line_) + " declares " +
                     plural(size, "connectivity entry", "connectivity entries")};
  const long cells = offset_count - 1;
  connectivity_.reserve(in_.plausibleCount(size, 2));
  cell_lines_.reserve(in_.plausibleCount(cells, 1));
  for (long c = 0; c < cells; ++c) {
    const size_t points =
        cell_begin_[static_cast<size_t>(c) + 1] - cell_begin_[static_cast<size_t>(c)];
    int cell_line = in_.lineNumber();
    for (size_t j = 0; j < points; ++j) {
      const long point = integerToken(
          listToken(entries, static_cast<long>(connectivity_.size())),
          [&] { return "point " + std::to_string(j) + " of cell " + std::to_string(c); });
      if (j == 0) cell_line = in_.lineNumber();
      connectivity_.push_back(checkedPoint(point, c));
    }
    cell_lines_.push_back(cell_line);
  }
}

void VtkReader::readCellTypes() {
  const int line = in_.lineNumber();
  refuseSecond(types_line_, "CELL_TYPES");
  if (cells_line_ == 0) in_.fail("CELL_TYPES before CELLS; the cells must come first");
  types_line_ = line;
  const long count = nextInteger("the number of cell types");
  const long cells = static_cast<long>(cell_lines_.size());
  if (count != cells) {
    in_.fail("CELL_TYPES declares " + plural(count, "cell", "cells") + ", CELLS " +
             atLine(cells_line_) + " declares " + std::to_string(cells));
  }
  const List list{"CELL_TYPES " + atLine(line) + " declares " +
                  plural(count, "cell type", "cell types")};
  std::map<long, long> skipped;  // cell type -> count
  for (long c = 0; c < count; ++c) {
    const long type =
        integerToken(listToken(list, c), [&] { return "the type of cell " + std::to_string(c); });
    const size_t cell = static_cast<size_t>(c);
    if (type != kTetraType) {
      ++skipped[type];
      continue;
    }
    const size_t begin = cell_begin_[cell];
    const size_t points = cell_begin_[cell + 1] - begin;
    if (points != 4) {
      in_.failAt(cell_lines_[cell], "cell " + std::to_string(c) +
                                        ": a tetrahedron (cell type 10) needs 4 points, found " +
                                        std::to_string(points));
    }
    raw_.tets.push_back(Tet{connectivity_[begin], connectivity_[begin + 1],
                            connectivity_[begin + 2], connectivity_[begin + 3]});
    raw_.origins.push_back({cell_lines_[cell], c});
  }
  std::string summary;
  for (const auto& [type, n] : skipped) {
    const std::string what = plural(n, "cell", "cells") + " of type " + std::to_string(type) +
                             " (" + cellTypeName(type) + ")";
    raw_.notes.push_back(in_.fileName() + ": skipped " + what);
    summary += (summary.empty() ? "" : ", ") + what;
  }
  if (raw_.tets.empty()) {
    in_.failAt(line, "no tetrahedra (cell type 10) among " + plural(count, "cell", "cells") + ": " +
                         summary +
                         (skipped.count(24) > 0 ? "; quadratic tetrahedra are not supported" : ""));
  }
  last_section_ = "CELL_TYPES";
  last_section_line_ = line;
}

// "FIELD <name> <#arrays>", then per array "<name> <#components> <#tuples> <type>" and its values.
// Only FIELD data before the grid is skipped this way; after it, parsing stops.
void VtkReader::skipField() {
  const int line = in_.lineNumber();
  next("the FIELD name");
  const long arrays = nextInteger("the number of FIELD arrays");
  if (arrays < 0) in_.fail("FIELD declares " + std::to_string(arrays) + " arrays");
  for (long a = 0; a < arrays; ++a) {
    const std::string_view name = next("the name of FIELD array " + std::to_string(a));
    if (name == "NULL_ARRAY") continue;
    if (iequals(name, "METADATA")) {  // array metadata: skip it and the rest of the FIELD
      skipToKeyword();
      break;
    }
    if (isKeyword(name)) {
      in_.fail("FIELD " + atLine(line) + " declares " + plural(arrays, "array", "arrays") +
               ", found " + std::to_string(a) + " before " + quoted(name));
    }
    const std::string array = "FIELD array " + quoted(name);
    const long components = nextInteger("the number of components of " + array);
    const long tuples = nextInteger("the number of tuples of " + array);
    const std::string_view type = next("the data type of " + array);
    if (components < 0 || tuples < 0) in_.fail(array + ": negative size");
    if (!isNumericType(type)) {  // strings: one per line, free text; skip up to the next section
      skipToKeyword();
      break;
    }
    if (components > 0 && tuples > LONG_MAX / components) in_.fail(array + ": too many values");
    const long values = components * tuples;
    const List list{array + " " + atLine(in_.lineNumber()) + " declares " +
                    plural(values, "value", "values")};
    for (long v = 0; v < values; ++v)
      listToken(list, v);
  }
  last_section_ = "FIELD";
  last_section_line_ = line;
}

// Skips METADATA (and anything else not understood) up to the next section keyword.
void VtkReader::skipToKeyword() {
  while (!atEnd()) {
    const std::string_view token = next("a section keyword");
    if (isKeyword(token) && !iequals(token, "METADATA")) {
      putBack(token);
      return;
    }
  }
}

RawTetMesh VtkReader::read() {
  readHeader();
  while (!atEnd()) {
    const std::string_view word = next("a section keyword");
    if (iequals(word, "POINTS")) {
      readPoints();
    } else if (iequals(word, "CELLS")) {
      readCells();
    } else if (iequals(word, "CELL_TYPES")) {
      readCellTypes();
    } else if (iequals(word, "METADATA")) {
      skipToKeyword();
    } else if (iequals(word, "FIELD") && types_line_ == 0) {
      skipField();
    } else if (isOneOf(word, {"POINT_DATA", "CELL_DATA", "FIELD"})) {
      break;  // data attributes after the grid: not needed for the mesh
    } else if (looksNumeric(word)) {
      in_.fail("unexpected value " + quoted(word) + " after the " + last_section_ + " section " +
               atLine(last_section_line_) + ": more values than it declares?");
    } else {
      in_.fail("unknown section " + quoted(word) +
               " (expected POINTS, CELLS, CELL_TYPES, POINT_DATA, CELL_DATA or FIELD)");
    }
  }
  if (points_line_ == 0) in_.fail("no POINTS section");
  if (cells_line_ == 0) in_.fail("no CELLS section");
  if (types_line_ == 0) in_.fail("no CELL_TYPES section after CELLS " + atLine(cells_line_));
  raw_.positions = std::move(positions_);
  raw_.element_file = in_.fileName();
  return std::move(raw_);
}

void appendField(std::string& out, const MeshField& field, size_t count) {
  assert(field.components == 1 || field.components == 3);
  assert(field.values.size() == count * static_cast<size_t>(field.components));
  std::string name = field.name.empty() ? std::string("field") : field.name;
  for (char& c : name) {
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r') c = '_';
  }
  char buffer[96];
  if (field.components == 1) {
    out += "SCALARS " + name + " double 1\nLOOKUP_TABLE default\n";
    for (double v : field.values) {
      std::snprintf(buffer, sizeof buffer, "%.17g\n", v);
      out += buffer;
    }
  } else {
    out += "VECTORS " + name + " double\n";
    for (size_t i = 0; i + 2 < field.values.size(); i += 3) {
      std::snprintf(buffer, sizeof buffer, "%.17g %.17g %.17g\n", field.values[i],
                    field.values[i + 1], field.values[i + 2]);
      out += buffer;
    }
  }
  (void)count;
}

}  // namespace

Result<RawTetMesh> parseVtk(std::string_view text, std::string_view file) {
  try {
    VtkReader reader(text, file);
    return reader.read();
  } catch (const detail::ParseFailure& failure) {
    return Error{failure.what()};
  }
}

std::string formatVtk(const TetMesh& mesh, const std::vector<Eigen::Vector3d>& positions,
                      const MeshFields& fields, std::string_view title) {
  assert(positions.size() == static_cast<size_t>(mesh.nodeCount()));
  const size_t nodes = positions.size();
  const size_t tets = static_cast<size_t>(mesh.tetCount());

  // The title is one line of at most 255 characters.
  std::string title_line(title.substr(0, 255));
  for (char& c : title_line) {
    if (c == '\n' || c == '\r') c = ' ';
  }

  std::string out =
      "# vtk DataFile Version 4.2\n" + title_line + "\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  char buffer[128];
  out += "POINTS " + std::to_string(nodes) + " double\n";
  for (const Eigen::Vector3d& p : positions) {
    std::snprintf(buffer, sizeof buffer, "%.17g %.17g %.17g\n", p.x(), p.y(), p.z());
    out += buffer;
  }
  out += "CELLS " + std::to_string(tets) + " " + std::to_string(5 * tets) + "\n";
  for (const Tet& tet : mesh.tets()) {
    std::snprintf(buffer, sizeof buffer, "4 %d %d %d %d\n", tet[0], tet[1], tet[2], tet[3]);
    out += buffer;
  }
  out += "CELL_TYPES " + std::to_string(tets) + "\n";
  for (size_t t = 0; t < tets; ++t)
    out += "10\n";

  if (!fields.node_fields.empty()) {
    out += "POINT_DATA " + std::to_string(nodes) + "\n";
    for (const MeshField& field : fields.node_fields)
      appendField(out, field, nodes);
  }
  if (!fields.tet_fields.empty()) {
    out += "CELL_DATA " + std::to_string(tets) + "\n";
    for (const MeshField& field : fields.tet_fields)
      appendField(out, field, tets);
  }
  return out;
}

}  // namespace torsion
