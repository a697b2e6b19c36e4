#include "torsion/mesh/gmsh_format.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "error_matchers.h"
#include "test_meshes.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/tetgen_format.h"

namespace torsion {
namespace {

using test::failsWith;

Result<RawTetMesh> parse(const std::string& text) {
  return parseGmsh(text, "m.msh");
}

// Two tets sharing the face (30, 20, 7), node tags out of order and sparse, plus a point, a line
// and two triangles to skip, a $PhysicalNames section before and a $NodeData section after.
// Dense indices in order of appearance: 10->0, 30->1, 20->2, 7->3, 99->4.
const std::string kMsh22 = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "skin"
3 2 "body"
$EndPhysicalNames
$Nodes
5
10 0 0 0
30 1 0 0
20 0 1 0
7 0 0 1
99 1 1 1
$EndNodes
$Elements
6
1 15 2 0 1 10
2 1 2 0 1 10 30
3 2 2 1 1 10 30 20
4 2 2 1 1 10 30 7
8 4 2 2 1 10 30 20 7
9 4 2 2 1 30 20 7 99
$EndElements
$NodeData
1
"temperature"
1
0.0
3
0
1
5
10 1.5
30 1.5
20 1.5
7 1.5
99 1.5
$EndNodeData
)";

// The same two tets in 4.1: three node blocks (a point, a parametric surface block with u v,
// a volume block) and three element blocks (a point, triangles, tets).
// Dense indices in order of appearance: 7->0, 30->1, 20->2, 10->3, 99->4.
const std::string kMsh41 = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$Entities
1 0 0 1
1 0 0 0 0
1 0 0 0 1 1 1 0 0
$EndEntities
$Nodes
3 5 7 99
0 1 0 1
7
0 0 1
2 4 1 2
30
20
1 0 0 0.5 0.5
0 1 0 0.25 0.75
3 1 0 2
10
99
0 0 0
1 1 1
$EndNodes
$Elements
3 5 1 12
0 1 15 1
1 7
2 4 2 2
5 7 30 20
6 30 20 99
3 1 4 2
11 10 30 20 7
12 30 20 7 99
$EndElements
)";

// The text with line `number` (1-based) replaced by `replacement` (which may hold several lines,
// or be empty to delete the line).
std::string withLine(const std::string& text, int number, const std::string& replacement) {
  std::istringstream in(text);
  std::string out, line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (n != number) {
      out += line + "\n";
    } else if (!replacement.empty()) {
      out += replacement + "\n";
    }
  }
  return out;
}

std::string withoutLine(const std::string& text, int number) {
  return withLine(text, number, "");
}

// Lines [first, last] of the text, 1-based.
std::string lines(const std::string& text, int first, int last) {
  std::istringstream in(text);
  std::string out, line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (n >= first && n <= last) out += line + "\n";
  }
  return out;
}

const std::vector<Eigen::Vector3d> kPositions22 = {
    {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}};
const std::vector<Eigen::Vector3d> kPositions41 = {
    {0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 1, 1}};

TEST(Gmsh, Reads22WithSparseTagsSkippingOtherElements) {
  Result<RawTetMesh> raw = parse(kMsh22);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions, kPositions22);
  ASSERT_EQ(raw.value().tets.size(), 2u);
  EXPECT_EQ(raw.value().tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(raw.value().tets[1], (Tet{1, 2, 3, 4}));
  EXPECT_EQ(raw.value().origins[0].line, 23);
  EXPECT_EQ(raw.value().origins[0].id, 8);
  EXPECT_EQ(raw.value().origins[1].line, 24);
  EXPECT_EQ(raw.value().origins[1].id, 9);
  EXPECT_EQ(raw.value().element_file, "m.msh");
  ASSERT_EQ(raw.value().notes.size(), 1u);
  EXPECT_EQ(raw.value().notes[0],
            "m.msh: skipped 1 element of type 1 (2-node line), 2 of type 2 (3-node triangle), 1 "
            "of type 15 (point)");

  Result<LoadedMesh> built = buildTetMesh(raw.value());
  ASSERT_TRUE(built.ok()) << built.error().message;
  EXPECT_EQ(built.value().mesh.tetCount(), 2);
  EXPECT_EQ(built.value().mesh.nodeCount(), 5);
}

TEST(Gmsh, Reads41WithSeveralBlocksAndParametricNodes) {
  Result<RawTetMesh> raw = parse(kMsh41);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions, kPositions41);
  ASSERT_EQ(raw.value().tets.size(), 2u);
  EXPECT_EQ(raw.value().tets[0], (Tet{3, 1, 2, 0}));
  EXPECT_EQ(raw.value().tets[1], (Tet{1, 2, 0, 4}));
  EXPECT_EQ(raw.value().origins[0].line, 33);
  EXPECT_EQ(raw.value().origins[0].id, 11);
  EXPECT_EQ(raw.value().origins[1].line, 34);
  EXPECT_EQ(raw.value().origins[1].id, 12);
  ASSERT_EQ(raw.value().notes.size(), 1u);
  EXPECT_EQ(raw.value().notes[0],
            "m.msh: skipped 2 elements of type 2 (3-node triangle), 1 of type 15 (point)");
  EXPECT_TRUE(buildTetMesh(raw.value()).ok());
}

TEST(Gmsh, Reads41ParametricNodesOnPointsCurvesAndVolumes) {
  // A parametric node carries one extra value per dimension of its entity: none on a point, u on
  // a curve, u v w in a volume.
  const std::string text = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$Nodes
3 5 7 99
0 1 1 1
7
0 0 1
1 4 1 2
30
20
1 0 0 0.5
0 1 0 0.25
3 1 1 2
10
99
0 0 0 0 0 0
1 1 1 1 1 1
$EndNodes
$Elements
1 2 11 12
3 1 4 2
11 10 30 20 7
12 30 20 7 99
$EndElements
)";
  Result<RawTetMesh> raw = parse(text);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions, kPositions41);
  EXPECT_TRUE(raw.value().notes.empty());
  EXPECT_TRUE(
      failsWith(parse(withLine(text, 12, "1 0 0")),
                {"m.msh:12:", "'x y z' and 1 parametric coordinate of node 30 (4 fields)"}));
  EXPECT_TRUE(failsWith(parse(withLine(text, 8, "0 0 1 0")),
                        {"m.msh:8:", "'x y z' of node 7 (3 fields), found 4 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(text, 9, "1 4 2 2")),
                        {"m.msh:9:", "parametric flag must be 0 or 1, found 2"}));
  EXPECT_TRUE(failsWith(parse(withLine(text, 9, "4 4 1 2")),
                        {"m.msh:9:", "entity dimension must be 0 to 3, found 4"}));
}

// Written by Gmsh 4.8.4 itself (one tet, "gmsh -3 tet.geo -format msh41 / msh22"), trailing
// spaces and empty node blocks (entities whose nodes live on their boundary) included.
const std::string kGmshWrote41 = R"($MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 2 "skin"
3 1 "body"
$EndPhysicalNames
$Entities
4 6 4 1
1 0 0 0 0 
2 1 0 0 0 
3 0 1 0 0 
4 0 0 1 0 
1 0 0 0 1 0 0 0 2 1 -2 
2 0 0 0 1 1 0 0 2 2 -3 
3 0 0 0 0 1 0 0 2 3 -1 
4 0 0 0 0 0 1 0 2 1 -4 
5 0 0 0 1 0 1 0 2 2 -4 
6 0 0 0 0 1 1 0 2 3 -4 
1 0 0 0 1 1 0 1 2 3 1 2 3 
2 0 0 0 1 0 1 1 2 3 1 5 -4 
3 0 0 0 1 1 1 1 2 3 2 6 -5 
4 0 0 0 0 1 1 1 2 3 3 4 -6 
1 0 0 0 1 1 1 1 1 4 1 2 3 4 
$EndEntities
$Nodes
9 4 1 4
0 1 0 1
1
0 0 0
0 2 0 1
2
1 0 0
0 3 0 1
3
0 1 0
0 4 0 1
4
0 0 1
2 1 0 0
2 2 0 0
2 3 0 0
2 4 0 0
3 1 0 0
$EndNodes
$Elements
5 5 1 5
2 1 2 1
1 1 2 3 
2 2 2 1
2 1 2 4 
2 3 2 1
3 2 3 4 
2 4 2 1
4 1 4 3 
3 1 4 1
5 1 3 4 2 
$EndElements
)";
const std::string kGmshWrote22 = R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
2
2 2 "skin"
3 1 "body"
$EndPhysicalNames
$Nodes
4
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
$EndNodes
$Elements
5
1 2 2 2 1 1 2 3
2 2 2 2 2 1 2 4
3 2 2 2 3 2 3 4
4 2 2 2 4 1 4 3
5 4 2 1 1 1 3 4 2
$EndElements
)";

TEST(Gmsh, ReadsFilesWrittenByGmsh) {
  for (const std::string* text : {&kGmshWrote41, &kGmshWrote22}) {
    Result<RawTetMesh> raw = parse(*text);
    ASSERT_TRUE(raw.ok()) << raw.error().message;
    EXPECT_EQ(raw.value().positions,
              (std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}));
    ASSERT_EQ(raw.value().tets.size(), 1u);
    EXPECT_EQ(raw.value().tets[0], (Tet{0, 2, 3, 1}));
    EXPECT_EQ(raw.value().origins[0].id, 5);
    EXPECT_EQ(raw.value().notes,
              std::vector<std::string>{"m.msh: skipped 4 elements of type 2 (3-node triangle)"});
    Result<LoadedMesh> built = buildTetMesh(raw.value());
    ASSERT_TRUE(built.ok()) << built.error().message;
    EXPECT_EQ(built.value().reoriented_tets, 0);
  }
  EXPECT_EQ(parse(kGmshWrote41).value().origins[0].line, 58);
  EXPECT_EQ(parse(kGmshWrote22).value().origins[0].line, 22);
}

TEST(Gmsh, AcceptsCrLfBlankLinesAndUnknownSections) {
  std::string text = "$Comments\nwritten by hand\n$EndComments\n" + kMsh41 +
                     "$Periodic\n0\n$EndPeriodic\n\n$SomethingNew\n1 2 3\n$EndSomethingNew\n";
  std::string crlf;
  for (char c : text)
    crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  Result<RawTetMesh> raw = parse(crlf);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().tets.size(), 2u);
  EXPECT_EQ(raw.value().origins[0].line, 36);
}

TEST(Gmsh, ElementsBeforeNodesAreResolved) {
  const std::string text = lines(kMsh22, 1, 3) + lines(kMsh22, 17, 25) + lines(kMsh22, 9, 16);
  Result<RawTetMesh> raw = parse(text);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().tets[1], (Tet{1, 2, 3, 4}));
  EXPECT_EQ(raw.value().origins[1].line, 11);
}

TEST(Gmsh, HigherOrderTetsAreSkippedWithANote) {
  const std::string text = withLine(kMsh22, 22, "4 11 2 2 1 10 30 20 7 1 2 3 4 5 6");
  Result<RawTetMesh> raw = parse(text);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().tets.size(), 2u);
  ASSERT_EQ(raw.value().notes.size(), 2u);
  EXPECT_EQ(raw.value().notes[0],
            "m.msh: skipped 1 element of type 1 (2-node line), 1 of type 2 (3-node triangle), 1 "
            "of type 15 (point)");
  EXPECT_EQ(raw.value().notes[1],
            "m.msh: skipped 1 element of type 11 (10-node second-order tetrahedron): higher-order "
            "tetrahedra are not supported, only 4-node ones");
}

TEST(Gmsh, UnknownElementTypesAreSkippedUnchecked) {
  Result<RawTetMesh> raw = parse(withLine(kMsh22, 22, "4 140 2 1 1 10 30 20 7 99 1 2"));
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_NE(raw.value().notes[0].find(", 1 of type 140"), std::string::npos)
      << raw.value().notes[0];
}

TEST(Gmsh, RoundTripsThroughItsWriter) {
  Result<RawTetMesh> cube = parseTetGen(test::kCubeNode, "cube.node", test::kCubeEle, "cube.ele");
  ASSERT_TRUE(cube.ok());
  Result<LoadedMesh> first = buildTetMesh(cube.value());
  ASSERT_TRUE(first.ok());
  const TetMesh& mesh = first.value().mesh;
  const std::string text = formatGmsh41(mesh);
  EXPECT_EQ(text.rfind("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 1\n", 0), 0u)
      << text;
  Result<RawTetMesh> again = parse(text);
  ASSERT_TRUE(again.ok()) << again.error().message << "\n" << text;
  EXPECT_EQ(again.value().positions, mesh.restPositions());
  EXPECT_EQ(again.value().tets, mesh.tets());
  EXPECT_TRUE(again.value().notes.empty());
  EXPECT_EQ(again.value().origins.back().id, mesh.tetCount());
}

TEST(Gmsh, RoundTripIsExactForAwkwardCoordinates) {
  const std::vector<Eigen::Vector3d> positions = {{0.1, 1.0 / 3.0, -2.5e-300},
                                                  {1e10 + 0.7, 0.2, 0.3},
                                                  {0.1, 1e10, 1.0 / 7.0},
                                                  {0.1, 0.2, 123456.789}};
  Tet tet{0, 1, 2, 3};
  if (sixSignedVolume(positions[0], positions[1], positions[2], positions[3]) < 0)
    tet = {0, 2, 1, 3};
  const TetMesh mesh(positions, {tet});
  Result<RawTetMesh> again = parse(formatGmsh41(mesh));
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again.value().positions, positions);
}

// ---- one test per fault class ----

TEST(GmshFaults, MissingMeshFormat) {
  EXPECT_TRUE(failsWith(parse(""), {"m.msh:0:", "missing '$MeshFormat'"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 9, 16)), {"m.msh:1:", "before '$MeshFormat'"}));
  EXPECT_TRUE(failsWith(parse("$NOD\n1\n1 0 0 0\n$ENDNOD\n"), {"m.msh:1:", "version 1"}));
  EXPECT_TRUE(failsWith(parse("solid cube\nfacet normal 0 0 1\n"),
                        {"m.msh:1:", "expected a section header", "'solid'"}));
}

TEST(GmshFaults, UnsupportedVersion) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 2, "4 0 8")),
                        {"m.msh:2:", "MSH version 4 is not supported", "2.2 and 4.1"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 2, "4.0 0 8")),
                        {"m.msh:2:", "MSH version 4.0 is not supported", "2.2 and 4.1"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 2, "2.1 0 8")), {"m.msh:2:", "MSH version 2.1"}));
  EXPECT_TRUE(
      failsWith(parse(withLine(kMsh22, 2, "two 0 8")), {"m.msh:2:", "MSH version", "'two'"}));
}

TEST(GmshFaults, BinaryRefused) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 2, "4.1 1 8")), {"m.msh:2:", "binary", "ASCII"}));
  EXPECT_TRUE(
      failsWith(parse(withLine(kMsh22, 2, "2.2 2 8")), {"m.msh:2:", "file-type must be 0"}));
}

TEST(GmshFaults, DataSize) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 2, "2.2 0 4")), {"m.msh:2:", "data-size 4"}));
}

TEST(GmshFaults, MalformedMeshFormat) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 2, "2.2 0")), {"m.msh:2:", "found 2 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 2, "2.2 0 8 1")), {"m.msh:2:", "found 4 fields"}));
  EXPECT_TRUE(failsWith(parse(withoutLine(kMsh22, 3)),
                        {"m.msh:3:", "expected '$EndMeshFormat'", "'$PhysicalNames'"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 3) + lines(kMsh22, 1, 3)),
                        {"m.msh:4:", "second '$MeshFormat'"}));
}

TEST(GmshFaults, MissingNodesOrElements) {
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 8)), {"m.msh:8:", "missing '$Nodes'"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 16)), {"m.msh:16:", "missing '$Elements'"}));
  EXPECT_TRUE(failsWith(parse(kMsh22 + lines(kMsh22, 9, 16)),
                        {"m.msh:41:", "second '$Nodes' section (the first is at line 9)"}));
}

TEST(GmshFaults, UnterminatedSection) {
  EXPECT_TRUE(failsWith(
      parse(lines(kMsh22, 1, 7)),
      {"m.msh:7:", "unterminated section '$PhysicalNames' (line 4)", "no '$EndPhysicalNames'"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 15)),
                        {"m.msh:15:", "unterminated section '$Nodes' (line 9)"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh41, 1, 34)),
                        {"m.msh:34:", "unterminated section '$Elements' (line 25)"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 3) + "$EndNodes\n"),
                        {"m.msh:4:", "'$EndNodes' without a matching '$Nodes'"}));
}

TEST(GmshFaults, CountsDoNotMatch22) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 10, "6")),
                        {"m.msh:16:", "unexpected '$EndNodes'", "declares 6 nodes, found 5"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 10, "4")),
                        {"m.msh:15:", "expected '$EndNodes' after the 4 nodes", "'99 1 1 1'"}));
  EXPECT_TRUE(
      failsWith(parse(withLine(kMsh22, 18, "7")), {"m.msh:25:", "declares 7 elements, found 6"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 23)),
                        {"m.msh:23:", "unexpected end of file in '$Elements' (line 17)",
                         "declares 6 elements, found 5"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 10, "-1")), {"m.msh:10:", "negative"}));
}

TEST(GmshFaults, CountsDoNotMatch41) {
  // numNodes larger than the blocks hold.
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 10, "3 6 7 99")),
                        {"m.msh:10:", "the header declares 6 nodes, its 3 entity blocks hold 5"}));
  // A block larger than what the header has left.
  EXPECT_TRUE(
      failsWith(parse(withLine(kMsh41, 10, "3 4 7 99")),
                {"m.msh:19:", "the block declares 2 nodes, more than the 1 left of the 4"}));
  // numEntityBlocks larger than the blocks present.
  EXPECT_TRUE(
      failsWith(parse(withLine(kMsh41, 10, "4 5 7 99")),
                {"m.msh:24:", "unexpected '$EndNodes'", "declares 4 entity blocks, found 3"}));
  // numEntityBlocks smaller than the blocks present.
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 10, "2 5 7 99")),
                        {"m.msh:10:", "declares 5 nodes, its 2 entity blocks hold 3"}));
  // numNodesInBlock smaller than the tags present: a tag line is read as a coordinate line.
  EXPECT_TRUE(failsWith(parse(withLine(withLine(kMsh41, 10, "3 4 7 99"), 14, "2 4 1 1")),
                        {"m.msh:16:", "'x y z' and 2 parametric coordinates of node 30",
                         "found 1 field", "(the block header, line 14, declares 1 node)"}));
  // numNodesInBlock larger than the tags present: a coordinate line is read as a tag line.
  EXPECT_TRUE(failsWith(parse(withLine(withLine(kMsh41, 10, "3 6 7 99"), 19, "3 1 0 3")),
                        {"m.msh:22:", "one node tag per line", "found 3 fields",
                         "(the block header, line 19, declares 3 nodes)"}));
  // numElementsInBlock larger than the lines present.
  EXPECT_TRUE(failsWith(parse(withLine(withLine(kMsh41, 26, "3 6 1 12"), 32, "3 1 4 3")),
                        {"m.msh:35:", "unexpected '$EndElements'",
                         "block header (line 32) declares 3 elements, found 2"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 26, "3 6 1 12")),
                        {"m.msh:26:", "declares 6 elements, its 3 entity blocks hold 5"}));
}

TEST(GmshFaults, TruncatedLine) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 12, "30 1 0")),
                        {"m.msh:12:", "'<node tag> <x> <y> <z>' (4 fields), found 3 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 12, "30 1 0 0 0")),
                        {"m.msh:12:", "(4 fields), found 5 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 17, "1 0 0 0.5")),
                        {"m.msh:17:", "parametric coordinates of node 30", "found 4 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 22, "0 0")),
                        {"m.msh:22:", "'x y z' of node 10", "found 2 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 11, "0 1 0")), {"m.msh:11:", "found 3 fields"}));
  EXPECT_TRUE(failsWith(
      parse(withLine(kMsh22, 21, "3 2 2 1 1 10 30")),
      {"m.msh:21:", "element 3 of type 2 (3-node triangle)", "expected 3 node tags, found 2"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 21, "3 2")), {"m.msh:21:", "found 2 fields"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 21, "3 2 9 1 1 10 30 20")),
                        {"m.msh:21:", "element 3: the line announces 9 tags"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 30, "5 7 30")),
                        {"m.msh:30:", "element 5 of type 2 (3-node triangle)", "found 2"}));
}

TEST(GmshFaults, NonNumericField) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 12, "30 1 zero 0")),
                        {"m.msh:12:", "coordinate y of node 30", "'zero'"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 23, "8 4 2 2 1 10 30 20 7.5")),
                        {"m.msh:23:", "a node tag of tet 8", "integer", "'7.5'"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 10, "five")),
                        {"m.msh:10:", "the number of nodes", "'five'"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 16, "x20")), {"m.msh:16:", "node tag", "'x20'"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 29, "2 4 tri 2")),
                        {"m.msh:29:", "the element type", "'tri'"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 10, "99999999999999999999999")),
                        {"m.msh:10:", "out of range"}));
}

TEST(GmshFaults, NonFiniteCoordinate) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 12, "30 nan 0 0")), {"m.msh:12:", "not finite"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 22, "0 -inf 0")), {"m.msh:22:", "not finite"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 17, "1 0 0 nan 0.5")),
                        {"m.msh:17:", "parametric coordinate of node 30", "not finite"}));
  EXPECT_TRUE(
      failsWith(parse(withLine(kMsh22, 12, "30 1e999 0 0")), {"m.msh:12:", "out of range"}));
}

TEST(GmshFaults, WrongNodeCountForTet) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 23, "8 4 2 2 1 10 30 20")),
                        {"m.msh:23:", "tet 8: expected 4 node tags, found 3"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 33, "11 10 30 20 7 99")),
                        {"m.msh:33:", "tet 11: expected 4 node tags, found 5"}));
}

TEST(GmshFaults, UnknownNodeTag) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 23, "8 4 2 2 1 10 30 912 7")),
                        {"m.msh:23:", "tet 8: vertex tag 912 is not a node of this file"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 34, "12 30 20 7 -1")),
                        {"m.msh:34:", "tet 12: vertex tag -1 is not a node"}));
}

TEST(GmshFaults, DuplicateOrInvalidTag) {
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 14, "30 0 0 1")),
                        {"m.msh:14:", "node tag 30 appears twice (first at line 12)"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 21, "7")),
                        {"m.msh:21:", "node tag 7 appears twice (first at line 12)"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 24, "8 4 2 2 1 30 20 7 99")),
                        {"m.msh:24:", "tet tag 8 appears twice (first at line 23)"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 12, "0 1 0 0")),
                        {"m.msh:12:", "node tag must be positive, found 0"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 33, "-11 10 30 20 7")),
                        {"m.msh:33:", "element tag must be positive, found -11"}));
}

TEST(GmshFaults, NoLinearTets) {
  const std::string surface_only =
      withLine(withLine(withLine(kMsh22, 18, "4"), 23, ""), 23, "");  // drops both tets
  EXPECT_TRUE(failsWith(parse(surface_only),
                        {"m.msh:18:", "no 4-node tetrahedra (element type 4) among 4 elements",
                         "2 of type 2 (3-node triangle)"}));
  const std::string quadratic = withLine(withLine(surface_only, 18, "5"), 22,
                                         "4 2 2 1 1 10 30 7\n5 11 2 2 1 1 2 3 4 5 6 7 8 9 10");
  EXPECT_TRUE(failsWith(parse(quadratic),
                        {"m.msh:18:", "among 5 elements", "1 of type 11 (10-node second-order",
                         "higher-order tetrahedra are not supported"}));
  EXPECT_TRUE(failsWith(parse(lines(kMsh22, 1, 17) + "0\n$EndElements\n"),
                        {"m.msh:18:", "among 0 elements"}));
}

TEST(GmshFaults, VersionMismatchedSectionLayout) {
  // A 4.1 body under a 2.2 header, and the other way round.
  EXPECT_TRUE(failsWith(parse(withLine(kMsh41, 2, "2.2 0 8")),
                        {"m.msh:10:", "looks like a version 4 '$Nodes' header"}));
  EXPECT_TRUE(failsWith(parse(withLine(kMsh22, 2, "4.1 0 8")), {"m.msh:10:", "found 1 field"}));
}

TEST(GmshFaults, EveryTruncationFailsCleanly) {
  // Cutting a valid file anywhere must give an error with a position or (at a section boundary
  // after $Elements) a valid mesh, never a crash.
  for (const std::string* text : {&kMsh22, &kMsh41}) {
    for (size_t n = 0; n < text->size(); ++n) {
      Result<RawTetMesh> raw = parse(text->substr(0, n));
      if (!raw.ok()) {
        EXPECT_EQ(raw.error().message.rfind("m.msh:", 0), 0u) << raw.error().message;
      }
    }
  }
}

}  // namespace
}  // namespace torsion
