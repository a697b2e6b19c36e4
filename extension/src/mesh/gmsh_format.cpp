#include "torsion/mesh/gmsh_format.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "text_scanner.h"

namespace torsion {

namespace {

using detail::plural;
using detail::quoted;
using detail::TextScanner;

constexpr long kLinearTet = 4;

struct ElementType {
  long type;
  long nodes;
  const char* name;
  bool higher_order_tet;
};

// The element types of the MSH format that Gmsh documents, with their node counts. Lines of these
// types are checked for their node count even though they are skipped; other types are skipped
// unchecked (their node count is unknown here).
constexpr ElementType kElementTypes[] = {
    {1, 2, "2-node line", false},
    {2, 3, "3-node triangle", false},
    {3, 4, "4-node quadrangle", false},
    {4, 4, "4-node tetrahedron", false},
    {5, 8, "8-node hexahedron", false},
    {6, 6, "6-node prism", false},
    {7, 5, "5-node pyramid", false},
    {8, 3, "3-node second-order line", false},
    {9, 6, "6-node second-order triangle", false},
    {10, 9, "9-node second-order quadrangle", false},
    {11, 10, "10-node second-order tetrahedron", true},
    {12, 27, "27-node second-order hexahedron", false},
    {13, 18, "18-node second-order prism", false},
    {14, 14, "14-node second-order pyramid", false},
    {15, 1, "point", false},
    {16, 8, "8-node second-order quadrangle", false},
    {17, 20, "20-node second-order hexahedron", false},
    {18, 15, "15-node second-order prism", false},
    {19, 13, "13-node second-order pyramid", false},
    {20, 9, "9-node third-order incomplete triangle", false},
    {21, 10, "10-node third-order triangle", false},
    {22, 12, "12-node fourth-order incomplete triangle", false},
    {23, 15, "15-node fourth-order triangle", false},
    {24, 15, "15-node fifth-order incomplete triangle", false},
    {25, 21, "21-node fifth-order triangle", false},
    {26, 4, "4-node third-order line", false},
    {27, 5, "5-node fourth-order line", false},
    {28, 6, "6-node fifth-order line", false},
    {29, 20, "20-node third-order tetrahedron", true},
    {30, 35, "35-node fourth-order tetrahedron", true},
    {31, 56, "56-node fifth-order tetrahedron", true},
    {92, 64, "64-node third-order hexahedron", false},
    {93, 125, "125-node fourth-order hexahedron", false},
};

const ElementType* findElementType(long type) {
  for (const ElementType& t : kElementTypes) {
    if (t.type == type) return &t;
  }
  return nullptr;
}

// "type 2 (3-node triangle)", or "type 42" for a type not in the table.
std::string describeType(long type) {
  const ElementType* known = findElementType(type);
  return "type " + std::to_string(type) + (known ? " (" + std::string(known->name) + ")" : "");
}

// A tet as read, its vertices still node tags; resolved to dense indices once all nodes are known.
struct PendingTet {
  std::array<long, 4> tags;
  ElementOrigin origin;
};

// Where a counted list stands, for messages about a list that ends early.
struct Progress {
  const char* items;  // plural noun: "nodes", "elements", "entity blocks", ...
  long declared;
  long found;
  int header_line;
  const char* header;  // "header" or "block header"
};

class GmshReader {
 public:
  GmshReader(std::string_view text, std::string file) : in_(text, std::move(file)) {}

  RawTetMesh read() {
    while (in_.nextLine()) {
      const std::string_view head = in_.tokens()[0];
      if (head[0] != '$') {
        in_.fail("expected a section header such as '$Nodes', found " + quoted(head));
      }
      requireFields(1, quoted(head) + " alone on its line");
      const std::string_view name = head.substr(1);
      if (name.size() > 3 && name.substr(0, 3) == "End") {
        in_.fail(quoted(head) + " without a matching '$" + std::string(name.substr(3)) + "'");
      }
      if (name == "NOD" || name == "ELM") {
        in_.fail(
            "MSH version 1 files ('$NOD', '$ELM') are not supported; supported versions are "
            "2.2 and 4.1");
      }
      const bool nodes = name == "Nodes";
      const bool elements = name == "Elements";
      if (name == "MeshFormat") {
        if (format_line_ > 0) {
          in_.fail("second '$MeshFormat' section (the first is at line " +
                   std::to_string(format_line_) + ")");
        }
        readMeshFormat();
      } else if (nodes || elements) {
        if (format_line_ == 0) {
          in_.fail(quoted(head) + " before '$MeshFormat': a Gmsh file starts with '$MeshFormat'");
        }
        int& seen = nodes ? nodes_line_ : elements_line_;
        if (seen > 0) {
          in_.fail("second " + quoted(head) + " section (the first is at line " +
                   std::to_string(seen) + ")");
        }
        seen = in_.lineNumber();
        if (nodes) {
          version41_ ? readNodes41() : readNodes22();
        } else {
          version41_ ? readElements41() : readElements22();
        }
      } else {
        skipSection(head);
      }
    }
    if (format_line_ == 0) in_.fail("missing '$MeshFormat' section: not a Gmsh .msh file");
    if (nodes_line_ == 0) in_.fail("missing '$Nodes' section");
    if (elements_line_ == 0) in_.fail("missing '$Elements' section");
    return finish();
  }

 private:
  // ---- Lines ----

  // Exactly n fields on the current line; `hint` is appended to the message when there are not.
  void requireFields(size_t n, std::string_view what, std::string_view hint = {}) const {
    const size_t found = in_.tokens().size();
    if (found == n) return;
    in_.fail("expected " + std::string(what) + " (" +
             plural(static_cast<long>(n), "field", "fields") + "), found " +
             plural(static_cast<long>(found), "field", "fields") + std::string(hint));
  }

  // The next line of the current section, which must not be a "$..." line.
  void requireBodyLine(const std::string& what) {
    if (!in_.nextLine()) {
      in_.fail("unexpected end of file in " + quoted(section_) + " (line " +
               std::to_string(section_line_) + "), expected " + what);
    }
    if (in_.tokens()[0][0] == '$')
      in_.fail("expected " + what + ", found " + quoted(in_.lineText()));
  }

  // The next line of a counted list; ending early names the count.
  void requireBodyLine(const Progress& p) {
    const bool more = in_.nextLine();
    if (more && in_.tokens()[0][0] != '$') return;
    const std::string shortfall =
        "the " + std::string(p.header) + " (line " + std::to_string(p.header_line) + ") declares " +
        std::to_string(p.declared) + " " + p.items + ", found " + std::to_string(p.found);
    if (!more) {
      in_.fail("unexpected end of file in " + quoted(section_) + " (line " +
               std::to_string(section_line_) + "): " + shortfall);
    }
    in_.fail("unexpected " + quoted(in_.lineText()) + ": " + shortfall);
  }

  void beginSection(std::string_view header) {
    section_ = std::string(header);
    section_line_ = in_.lineNumber();
  }

  // The line after a section's content must be its "$End..." line.
  void requireSectionEnd(const std::string& after) {
    const std::string end = "$End" + section_.substr(1);
    if (!in_.nextLine()) {
      in_.fail("unterminated section " + quoted(section_) + " (line " +
               std::to_string(section_line_) + "): no " + quoted(end) +
               " before the end of the file");
    }
    if (in_.lineText() != end) {
      in_.fail("expected " + quoted(end) + " " + after + ", found " + quoted(in_.lineText()));
    }
  }

  void skipSection(std::string_view header) {
    beginSection(header);
    const std::string end = "$End" + section_.substr(1);
    while (in_.nextLine()) {
      if (in_.lineText() == end) return;
    }
    in_.fail("unterminated section " + quoted(section_) + " (line " +
             std::to_string(section_line_) + "): no " + quoted(end) +
             " before the end of the file");
  }

  long parseCount(std::string_view token, const std::string& what) const {
    const long n = in_.parseInteger(token, what);
    if (n < 0) in_.fail(what + " is negative (" + std::to_string(n) + ")");
    return n;
  }

  // ---- $MeshFormat ----

  void readMeshFormat() {
    beginSection("$MeshFormat");
    format_line_ = section_line_;
    const std::string what = "'<version> <file-type> <data-size>'";
    requireBodyLine(what);
    requireFields(3, what);
    const auto& t = in_.tokens();
    const double version = in_.parseReal(t[0], "the MSH version");
    if (version != 2.2 && version != 4.1) {
      in_.fail("MSH version " + std::string(t[0].substr(0, 20)) +
               " is not supported; supported versions are 2.2 and 4.1 (re-export the mesh from "
               "Gmsh in one of them)");
    }
    version41_ = version == 4.1;
    const long file_type = in_.parseInteger(t[1], "the file type");
    if (file_type == 1) {
      in_.fail(
          "binary .msh files are not supported; save the mesh as ASCII (Gmsh option "
          "Mesh.Binary = 0)");
    }
    if (file_type != 0) {
      in_.fail("file-type must be 0 (ASCII) or 1 (binary), found " + std::to_string(file_type));
    }
    const long data_size = in_.parseInteger(t[2], "the data size");
    if (data_size != 8) {
      in_.fail("data-size " + std::to_string(data_size) +
               " is not supported; it must be 8 (double precision)");
    }
    requireSectionEnd("after the format line");
  }

  // ---- $Nodes ----

  void addNodeTag(long tag) {
    if (tag <= 0) in_.fail("node tag must be positive, found " + std::to_string(tag));
    if (node_tags_.size() >= static_cast<size_t>(INT_MAX)) in_.fail("too many nodes");
    node_tags_.push_back(tag);
    node_lines_.push_back(in_.lineNumber());
  }

  Eigen::Vector3d parsePoint(size_t first, long tag) const {
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) {
      p[d] =
          in_.parseReal(in_.tokens()[first + static_cast<size_t>(d)],
                        std::string("coordinate ") + "xyz"[d] + " of node " + std::to_string(tag));
    }
    return p;
  }

  void reserveNodes(long count, size_t min_bytes) {
    const size_t n = in_.plausibleCount(count, min_bytes);
    node_tags_.reserve(node_tags_.size() + n);
    node_lines_.reserve(node_lines_.size() + n);
    positions_.reserve(positions_.size() + n);
  }

  // 2.2: "<number of nodes>", then "<node tag> <x> <y> <z>" per node.
  void readNodes22() {
    beginSection("$Nodes");
    const std::string what = "the number of nodes";
    requireBodyLine(what);
    if (in_.tokens().size() == 4) {
      in_.fail("expected " + what +
               " (1 field), found 4 fields; the file says version 2.2, "
               "but this looks like a version 4 '$Nodes' header");
    }
    requireFields(1, what);
    const long count = parseCount(in_.tokens()[0], what);
    const int header_line = in_.lineNumber();
    reserveNodes(count, 8);
    for (long i = 0; i < count; ++i) {
      requireBodyLine(Progress{"nodes", count, i, header_line, "header"});
      requireFields(4, "'<node tag> <x> <y> <z>'");
      const long tag = in_.parseInteger(in_.tokens()[0], "the node tag");
      addNodeTag(tag);
      positions_.push_back(parsePoint(1, tag));
    }
    requireSectionEnd("after the " + std::to_string(count) + " nodes the header (line " +
                      std::to_string(header_line) + ") declares");
  }

  // 4.1: "<numEntityBlocks> <numNodes> <minNodeTag> <maxNodeTag>", then per block
  // "<entityDim> <entityTag> <parametric> <numNodesInBlock>", that many tag lines, and that many
  // coordinate lines "x y z" (followed by entityDim parametric coordinates when parametric is 1).
  void readNodes41() {
    beginSection("$Nodes");
    const std::string what = "'<numEntityBlocks> <numNodes> <minNodeTag> <maxNodeTag>'";
    requireBodyLine(what);
    requireFields(4, what);
    const long blocks = parseCount(in_.tokens()[0], "the number of entity blocks");
    const long total = parseCount(in_.tokens()[1], "the number of nodes");
    in_.parseInteger(in_.tokens()[2], "the minimum node tag");
    in_.parseInteger(in_.tokens()[3], "the maximum node tag");
    const int header_line = in_.lineNumber();
    reserveNodes(total, 8);
    long read = 0;
    for (long b = 0; b < blocks; ++b) {
      requireBodyLine(Progress{"entity blocks", blocks, b, header_line, "header"});
      requireFields(4, "'<entityDim> <entityTag> <parametric> <numNodesInBlock>'");
      const auto& t = in_.tokens();
      const long dim = in_.parseInteger(t[0], "the entity dimension");
      in_.parseInteger(t[1], "the entity tag");
      const long parametric = in_.parseInteger(t[2], "the parametric flag");
      const long n = parseCount(t[3], "the number of nodes in the block");
      if (dim < 0 || dim > 3)
        in_.fail("entity dimension must be 0 to 3, found " + std::to_string(dim));
      if (parametric != 0 && parametric != 1) {
        in_.fail("the parametric flag must be 0 or 1, found " + std::to_string(parametric));
      }
      if (n > total - read) {
        in_.fail("the block declares " + std::to_string(n) + " nodes, more than the " +
                 std::to_string(total - read) + " left of the " + std::to_string(total) +
                 " the header (line " + std::to_string(header_line) + ") declares");
      }
      const int block_line = in_.lineNumber();
      const size_t first = node_tags_.size();
      // A wrong numNodesInBlock shifts tag lines into coordinate lines or back: say so.
      const std::string count_hint = " (the block header, line " + std::to_string(block_line) +
                                     ", declares " + plural(n, "node", "nodes") + ")";
      for (long i = 0; i < n; ++i) {
        requireBodyLine(Progress{"node tags", n, i, block_line, "block header"});
        if (in_.tokens().size() != 1) requireFields(1, "one node tag per line", count_hint);
        addNodeTag(in_.parseInteger(in_.tokens()[0], "the node tag"));
      }
      const size_t fields = 3 + (parametric == 1 ? static_cast<size_t>(dim) : 0);
      const std::string coordinates = parametric == 1 && dim > 0
                                          ? "'x y z' and " + std::to_string(dim) +
                                                " parametric coordinate" + (dim == 1 ? "" : "s")
                                          : "'x y z'";
      for (long i = 0; i < n; ++i) {
        requireBodyLine(Progress{"coordinate lines", n, i, block_line, "block header"});
        const long tag = node_tags_[first + static_cast<size_t>(i)];
        if (in_.tokens().size() != fields) {
          requireFields(fields, coordinates + " of node " + std::to_string(tag), count_hint);
        }
        positions_.push_back(parsePoint(0, tag));
        for (size_t k = 3; k < fields; ++k) {
          in_.parseReal(in_.tokens()[k], "a parametric coordinate of node " + std::to_string(tag));
        }
      }
      read += n;
    }
    if (read != total) {
      in_.failAt(header_line, "the header declares " + std::to_string(total) + " nodes, its " +
                                  plural(blocks, "entity block holds ", "entity blocks hold ") +
                                  std::to_string(read));
    }
    requireSectionEnd("after the " + plural(blocks, "entity block", "entity blocks") +
                      " the header (line " + std::to_string(header_line) + ") declares");
  }

  // ---- $Elements ----

  long parseElementTag(std::string_view token) const {
    const long tag = in_.parseInteger(token, "the element tag");
    if (tag <= 0) in_.fail("element tag must be positive, found " + std::to_string(tag));
    return tag;
  }

  // One element: its tag, type and node tags (tokens [first, end) of the current line).
  void addElement(long tag, long type, size_t first) {
    const auto& t = in_.tokens();
    const size_t n = t.size() - first;
    ++element_count_;
    if (type == kLinearTet) {
      if (n != 4) {
        in_.fail("tet " + std::to_string(tag) + ": expected 4 node tags, found " +
                 std::to_string(n));
      }
      PendingTet tet;
      const std::string what = "a node tag of tet " + std::to_string(tag);
      for (size_t k = 0; k < 4; ++k)
        tet.tags[k] = in_.parseInteger(t[first + k], what);
      tet.origin = {in_.lineNumber(), tag};
      tets_.push_back(tet);
      return;
    }
    const ElementType* known = findElementType(type);
    if (known && static_cast<long>(n) != known->nodes) {
      in_.fail("element " + std::to_string(tag) + " of " + describeType(type) + ": expected " +
               std::to_string(known->nodes) + " node tags, found " + std::to_string(n));
    }
    ++skipped_[type];
  }

  // 2.2: "<number of elements>", then
  // "<element tag> <type> <number of tags> <tag>... <node tag>..." per element.
  void readElements22() {
    beginSection("$Elements");
    const std::string what = "the number of elements";
    requireBodyLine(what);
    if (in_.tokens().size() == 4) {
      in_.fail("expected " + what +
               " (1 field), found 4 fields; the file says version 2.2, "
               "but this looks like a version 4 '$Elements' header");
    }
    requireFields(1, what);
    const long count = parseCount(in_.tokens()[0], what);
    elements_header_line_ = in_.lineNumber();
    for (long i = 0; i < count; ++i) {
      requireBodyLine(Progress{"elements", count, i, elements_header_line_, "header"});
      in_.requireTokens(3, "'<element tag> <type> <number of tags> <tags> <node tags>'");
      const auto& t = in_.tokens();
      const long tag = parseElementTag(t[0]);
      const long type = in_.parseInteger(t[1], "the type of element " + std::to_string(tag));
      const long tags =
          in_.parseInteger(t[2], "the number of tags of element " + std::to_string(tag));
      if (tags < 0 || static_cast<size_t>(tags) > t.size() - 3) {
        in_.fail("element " + std::to_string(tag) + ": the line announces " + std::to_string(tags) +
                 " tags but has " + std::to_string(t.size() - 3) + " fields after the count");
      }
      addElement(tag, type, 3 + static_cast<size_t>(tags));
    }
    requireSectionEnd("after the " + std::to_string(count) + " elements the header (line " +
                      std::to_string(elements_header_line_) + ") declares");
  }

  // 4.1: "<numEntityBlocks> <numElements> <minElementTag> <maxElementTag>", then per block
  // "<entityDim> <entityTag> <elementType> <numElementsInBlock>" and that many element lines
  // "<element tag> <node tag>...".
  void readElements41() {
    beginSection("$Elements");
    const std::string what = "'<numEntityBlocks> <numElements> <minElementTag> <maxElementTag>'";
    requireBodyLine(what);
    requireFields(4, what);
    const long blocks = parseCount(in_.tokens()[0], "the number of entity blocks");
    const long total = parseCount(in_.tokens()[1], "the number of elements");
    in_.parseInteger(in_.tokens()[2], "the minimum element tag");
    in_.parseInteger(in_.tokens()[3], "the maximum element tag");
    elements_header_line_ = in_.lineNumber();
    long read = 0;
    for (long b = 0; b < blocks; ++b) {
      requireBodyLine(Progress{"entity blocks", blocks, b, elements_header_line_, "header"});
      requireFields(4, "'<entityDim> <entityTag> <elementType> <numElementsInBlock>'");
      const auto& t = in_.tokens();
      const long dim = in_.parseInteger(t[0], "the entity dimension");
      in_.parseInteger(t[1], "the entity tag");
      const long type = in_.parseInteger(t[2], "the element type");
      const long n = parseCount(t[3], "the number of elements in the block");
      if (dim < 0 || dim > 3)
        in_.fail("entity dimension must be 0 to 3, found " + std::to_string(dim));
      if (n > total - read) {
        in_.fail("the block declares " + std::to_string(n) + " elements, more than the " +
                 std::to_string(total - read) + " left of the " + std::to_string(total) +
                 " the header (line " + std::to_string(elements_header_line_) + ") declares");
      }
      if (type == kLinearTet) tets_.reserve(tets_.size() + in_.plausibleCount(n, 10));
      const int block_line = in_.lineNumber();
      for (long i = 0; i < n; ++i) {
        requireBodyLine(Progress{"elements", n, i, block_line, "block header"});
        addElement(parseElementTag(in_.tokens()[0]), type, 1);
      }
      read += n;
    }
    if (read != total) {
      in_.failAt(elements_header_line_,
                 "the header declares " + std::to_string(total) + " elements, its " +
                     plural(blocks, "entity block holds ", "entity blocks hold ") +
                     std::to_string(read));
    }
    requireSectionEnd("after the " + plural(blocks, "entity block", "entity blocks") +
                      " the header (line " + std::to_string(elements_header_line_) + ") declares");
  }

  // ---- Result ----

  // "120 elements of type 2 (3-node triangle), 4 of type 15 (point)" for the types `select`s.
  template <class Select>
  std::string skippedList(Select select) const {
    std::string list;
    for (const auto& [type, count] : skipped_) {
      if (!select(type)) continue;
      list += list.empty() ? plural(count, "element", "elements") : std::to_string(count);
      list += " of " + describeType(type) + ", ";
    }
    if (!list.empty()) list.resize(list.size() - 2);
    return list;
  }

  static bool isHigherOrderTet(long type) {
    const ElementType* known = findElementType(type);
    return known != nullptr && known->higher_order_tet;
  }

  // (tag, position) pairs sorted by tag; fails at the later line of a repeated tag.
  std::vector<std::pair<long, int>> sortedUniqueTags(const std::vector<long>& tags,
                                                     const std::vector<int>& lines,
                                                     const char* noun) const {
    std::vector<std::pair<long, int>> sorted(tags.size());
    for (size_t i = 0; i < tags.size(); ++i)
      sorted[i] = {tags[i], static_cast<int>(i)};
    std::sort(sorted.begin(), sorted.end());
    int repeat_line = 0, first_line = 0;
    long repeated = 0;
    for (size_t i = 0; i + 1 < sorted.size(); ++i) {
      if (sorted[i].first != sorted[i + 1].first) continue;
      const int line = lines[static_cast<size_t>(sorted[i + 1].second)];
      if (repeat_line == 0 || line < repeat_line) {
        repeat_line = line;
        first_line = lines[static_cast<size_t>(sorted[i].second)];
        repeated = sorted[i].first;
      }
    }
    if (repeat_line > 0) {
      in_.failAt(repeat_line, std::string(noun) + " tag " + std::to_string(repeated) +
                                  " appears twice (first at line " + std::to_string(first_line) +
                                  ")");
    }
    return sorted;
  }

  RawTetMesh finish() {
    const std::string higher_order = skippedList(isHigherOrderTet);
    const std::string others = skippedList([](long type) { return !isHigherOrderTet(type); });
    if (tets_.empty()) {
      std::string all = skippedList([](long) { return true; });
      in_.failAt(elements_header_line_,
                 "no 4-node tetrahedra (element type 4) among " +
                     plural(element_count_, "element", "elements") +
                     (all.empty() ? "" : " (found " + all + ")") +
                     (higher_order.empty()
                          ? ""
                          : "; higher-order tetrahedra are not supported, mesh with order 1"));
    }

    // Node tags -> dense indices (order of appearance), by binary search in the sorted tags.
    const std::vector<std::pair<long, int>> sorted =
        sortedUniqueTags(node_tags_, node_lines_, "node");
    {
      std::vector<long> tet_tags(tets_.size());
      std::vector<int> tet_lines(tets_.size());
      for (size_t t = 0; t < tets_.size(); ++t) {
        tet_tags[t] = tets_[t].origin.id;
        tet_lines[t] = tets_[t].origin.line;
      }
      sortedUniqueTags(tet_tags, tet_lines, "tet");
    }

    RawTetMesh raw;
    raw.element_file = in_.fileName();
    raw.tets.reserve(tets_.size());
    raw.origins.reserve(tets_.size());
    for (const PendingTet& pending : tets_) {
      Tet tet;
      for (size_t k = 0; k < 4; ++k) {
        const long tag = pending.tags[k];
        auto it = std::lower_bound(sorted.begin(), sorted.end(), std::make_pair(tag, INT_MIN));
        if (it == sorted.end() || it->first != tag) {
          in_.failAt(pending.origin.line, "tet " + std::to_string(pending.origin.id) +
                                              ": vertex tag " + std::to_string(tag) +
                                              " is not a node of this file");
        }
        tet[k] = it->second;
      }
      raw.tets.push_back(tet);
      raw.origins.push_back(pending.origin);
    }
    raw.positions = std::move(positions_);
    if (!others.empty()) raw.notes.push_back(in_.fileName() + ": skipped " + others);
    if (!higher_order.empty()) {
      raw.notes.push_back(in_.fileName() + ": skipped " + higher_order +
                          ": higher-order tetrahedra are not supported, only 4-node ones");
    }
    return raw;
  }

  TextScanner in_;
  bool version41_ = false;
  std::string section_;  // header of the section being read, e.g. "$Nodes"
  int section_line_ = 0;
  int format_line_ = 0, nodes_line_ = 0, elements_line_ = 0;  // 0: not seen yet
  int elements_header_line_ = 0;                              // the element count line

  std::vector<long> node_tags_;  // in order of appearance; the index is the dense node index
  std::vector<int> node_lines_;  // line of each node's tag
  std::vector<Eigen::Vector3d> positions_;
  std::vector<PendingTet> tets_;
  std::map<long, long> skipped_;  // element type -> number of elements skipped
  long element_count_ = 0;
};

}  // namespace

Result<RawTetMesh> parseGmsh(std::string_view text, std::string_view file) {
  try {
    GmshReader reader(text, std::string(file));
    return reader.read();
  } catch (const detail::ParseFailure& failure) {
    return Error{failure.what()};
  }
}

std::string formatGmsh41(const TetMesh& mesh) {
  const int nodes = mesh.nodeCount();
  const int tets = mesh.tetCount();
  char buffer[256];
  std::string out = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";

  // One volume entity (tag 1) holding every node and tet: "<tag> <bounding box>
  // <#physical tags> <#bounding surfaces>".
  const Eigen::Vector3d lo = nodes > 0 ? mesh.boundsMin() : Eigen::Vector3d::Zero();
  const Eigen::Vector3d hi = nodes > 0 ? mesh.boundsMax() : Eigen::Vector3d::Zero();
  std::snprintf(buffer, sizeof buffer, "1 %.17g %.17g %.17g %.17g %.17g %.17g 0 0\n", lo.x(),
                lo.y(), lo.z(), hi.x(), hi.y(), hi.z());
  out += "$Entities\n0 0 0 1\n";
  out += buffer;
  out += "$EndEntities\n";

  out += "$Nodes\n";
  if (nodes > 0) {
    std::snprintf(buffer, sizeof buffer, "1 %d 1 %d\n3 1 0 %d\n", nodes, nodes, nodes);
    out += buffer;
    for (int n = 1; n <= nodes; ++n)
      out += std::to_string(n) + "\n";
    for (const Eigen::Vector3d& p : mesh.restPositions()) {
      std::snprintf(buffer, sizeof buffer, "%.17g %.17g %.17g\n", p.x(), p.y(), p.z());
      out += buffer;
    }
  } else {
    out += "0 0 0 0\n";
  }
  out += "$EndNodes\n";

  out += "$Elements\n";
  if (tets > 0) {
    std::snprintf(buffer, sizeof buffer, "1 %d 1 %d\n3 1 4 %d\n", tets, tets, tets);
    out += buffer;
    for (int t = 0; t < tets; ++t) {
      const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
      std::snprintf(buffer, sizeof buffer, "%d %d %d %d %d\n", t + 1, tet[0] + 1, tet[1] + 1,
                    tet[2] + 1, tet[3] + 1);
      out += buffer;
    }
  } else {
    out += "0 0 0 0\n";
  }
  out += "$EndElements\n";
  return out;
}

}  // namespace torsion
