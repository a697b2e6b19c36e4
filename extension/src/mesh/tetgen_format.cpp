#include "torsion/mesh/tetgen_format.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include "text_scanner.h"

namespace torsion {

namespace {

using detail::TextScanner;

// More per-point attributes than this is no mesh we can use; it also keeps field counts small.
constexpr long kMaxAttributes = 1000;

// Each entry of a .node or .ele list is at least one short line ("1\n"): what a header count is
// trusted for (TextScanner::plausibleCount).
constexpr size_t kMinCharsPerEntry = 2;

struct NodeTable {
  std::vector<Eigen::Vector3d> positions;
  long first_index = 0;  // 0 or 1: TetGen's files use the first point's index as the base
};

NodeTable parseNodes(TextScanner& in) {
  in.requireLine("the .node header '<#points> <dimension> <#attributes> <#markers>'");
  in.requireTokens(1, "the .node header '<#points> <dimension> <#attributes> <#markers>'");
  const auto& header = in.tokens();
  const long count = in.parseInteger(header[0], "the number of points");
  const long dimension = header.size() > 1 ? in.parseInteger(header[1], "the dimension") : 3;
  const long attributes =
      header.size() > 2 ? in.parseInteger(header[2], "the number of attributes") : 0;
  const long markers =
      header.size() > 3 ? in.parseInteger(header[3], "the number of boundary markers") : 0;
  if (count <= 0)
    in.fail("the header declares " + std::to_string(count) + " points; a mesh needs some");
  if (dimension != 3)
    in.fail("dimension is " + std::to_string(dimension) + "; only 3 is supported");
  if (attributes < 0 || attributes > kMaxAttributes) {
    in.fail("number of attributes " + std::to_string(attributes) + " is out of range [0, " +
            std::to_string(kMaxAttributes) + "]");
  }
  if (markers != 0 && markers != 1)
    in.fail("boundary markers must be 0 or 1, found " + std::to_string(markers));
  const int header_line = in.lineNumber();

  NodeTable table;
  table.positions.reserve(in.plausibleCount(count, kMinCharsPerEntry));
  const size_t fields = static_cast<size_t>(4 + attributes + markers);
  for (long i = 0; i < count; ++i) {
    if (!in.nextLine()) {
      in.fail("unexpected end of file: the header (line " + std::to_string(header_line) +
              ") declares " + std::to_string(count) + " points, found " + std::to_string(i));
    }
    in.requireTokens(4, "'<index> <x> <y> <z>' for point " + std::to_string(i));
    if (in.tokens().size() > fields) {
      in.fail("point line has " + std::to_string(in.tokens().size()) +
              " fields, the header allows " + std::to_string(fields));
    }
    const long index = in.parseInteger(in.tokens()[0], "the point index");
    if (i == 0) {
      if (index != 0 && index != 1)
        in.fail("the first point index must be 0 or 1, found " + std::to_string(index));
      table.first_index = index;
    } else if (index != table.first_index + i) {
      in.fail("point index " + std::to_string(index) + " out of sequence, expected " +
              std::to_string(table.first_index + i));
    }
    Eigen::Vector3d p;
    for (int d = 0; d < 3; ++d) {
      p[d] = in.parseReal(
          in.tokens()[static_cast<size_t>(1 + d)],
          std::string("coordinate ") + "xyz"[d] + " of point " + std::to_string(index));
    }
    for (size_t a = 4; a < in.tokens().size(); ++a)
      in.parseReal(in.tokens()[a], "a point attribute");
    table.positions.push_back(p);
  }
  if (in.nextLine()) {
    in.fail("more point lines than the " + std::to_string(count) + " the header (line " +
            std::to_string(header_line) + ") declares");
  }
  return table;
}

void parseElements(TextScanner& in, const NodeTable& nodes, RawTetMesh& raw) {
  in.requireLine("the .ele header '<#tetrahedra> <nodes per tet> <#attributes>'");
  const auto& header = in.tokens();
  const long count = in.parseInteger(header[0], "the number of tetrahedra");
  const long per_tet =
      header.size() > 1 ? in.parseInteger(header[1], "the nodes per tetrahedron") : 4;
  const long attributes =
      header.size() > 2 ? in.parseInteger(header[2], "the number of attributes") : 0;
  if (count <= 0)
    in.fail("the header declares " + std::to_string(count) + " tetrahedra; a mesh needs some");
  if (per_tet == 10)
    in.fail("quadratic (10-node) tetrahedra are not supported; mesh with 4-node tets");
  if (per_tet != 4) in.fail("nodes per tetrahedron is " + std::to_string(per_tet) + "; must be 4");
  if (attributes < 0 || attributes > kMaxAttributes) {
    in.fail("number of attributes " + std::to_string(attributes) + " is out of range [0, " +
            std::to_string(kMaxAttributes) + "]");
  }
  const int header_line = in.lineNumber();

  const long node_count = static_cast<long>(nodes.positions.size());
  const size_t fields = static_cast<size_t>(5 + attributes);
  raw.tets.reserve(in.plausibleCount(count, kMinCharsPerEntry));
  raw.origins.reserve(in.plausibleCount(count, kMinCharsPerEntry));
  long first_index = 0;
  for (long i = 0; i < count; ++i) {
    if (!in.nextLine()) {
      in.fail("unexpected end of file: the header (line " + std::to_string(header_line) +
              ") declares " + std::to_string(count) + " tetrahedra, found " + std::to_string(i));
    }
    in.requireTokens(5, "'<index> <n0> <n1> <n2> <n3>'");
    if (in.tokens().size() > fields) {
      in.fail("tetrahedron line has " + std::to_string(in.tokens().size()) +
              " fields, the header allows " + std::to_string(fields));
    }
    const long index = in.parseInteger(in.tokens()[0], "the tetrahedron index");
    if (i == 0) {
      if (index != 0 && index != 1)
        in.fail("the first tet index must be 0 or 1, found " + std::to_string(index));
      first_index = index;
    } else if (index != first_index + i) {
      in.fail("tet index " + std::to_string(index) + " out of sequence, expected " +
              std::to_string(first_index + i));
    }
    Tet tet;
    for (size_t k = 0; k < 4; ++k) {
      const long v =
          in.parseInteger(in.tokens()[1 + k], "a vertex of tet " + std::to_string(index));
      // Compare before subtracting: v may be any long.
      const bool in_range = v >= nodes.first_index && v - nodes.first_index < node_count;
      const long zero_based = in_range ? v - nodes.first_index : -1;
      if (!in_range) {
        in.fail("tet " + std::to_string(index) + ": vertex " + std::to_string(v) +
                (v < nodes.first_index ? " < first point index " + std::to_string(nodes.first_index)
                 : nodes.first_index == 0
                     ? " >= vertex count " + std::to_string(node_count)
                     : " > vertex count " + std::to_string(node_count) + " (indices are 1-based)"));
      }
      tet[k] = static_cast<int>(zero_based);
    }
    for (size_t a = 5; a < in.tokens().size(); ++a)
      in.parseReal(in.tokens()[a], "a tet attribute");
    raw.tets.push_back(tet);
    raw.origins.push_back({in.lineNumber(), index});
  }
  if (in.nextLine()) {
    in.fail("more tetrahedron lines than the " + std::to_string(count) + " the header (line " +
            std::to_string(header_line) + ") declares");
  }
}

}  // namespace

Result<RawTetMesh> parseTetGen(std::string_view node_text, std::string_view node_file,
                               std::string_view ele_text, std::string_view ele_file) {
  try {
    TextScanner nodes_in(node_text, std::string(node_file), '#');
    NodeTable nodes = parseNodes(nodes_in);
    RawTetMesh raw;
    raw.element_file = std::string(ele_file);
    TextScanner ele_in(ele_text, raw.element_file, '#');
    parseElements(ele_in, nodes, raw);
    raw.positions = std::move(nodes.positions);
    return raw;
  } catch (const detail::ParseFailure& failure) {
    return Error{failure.what()};
  }
}

TetGenText formatTetGen(const TetMesh& mesh) {
  TetGenText out;
  char buffer[128];
  out.node = std::to_string(mesh.nodeCount()) + " 3 0 0\n";
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    const Eigen::Vector3d& p = mesh.restPositions()[static_cast<size_t>(n)];
    std::snprintf(buffer, sizeof buffer, "%d %.17g %.17g %.17g\n", n, p.x(), p.y(), p.z());
    out.node += buffer;
  }
  out.ele = std::to_string(mesh.tetCount()) + " 4 0\n";
  for (int t = 0; t < mesh.tetCount(); ++t) {
    const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
    std::snprintf(buffer, sizeof buffer, "%d %d %d %d %d\n", t, tet[0], tet[1], tet[2], tet[3]);
    out.ele += buffer;
  }
  return out;
}

}  // namespace torsion
