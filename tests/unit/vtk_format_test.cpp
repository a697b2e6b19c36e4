#include "torsion/mesh/vtk_format.h"

#include <gtest/gtest.h>

#include <random>
#include <string>

#include "error_matchers.h"
#include "test_meshes.h"
#include "torsion/mesh/tet_mesh_builder.h"
#include "torsion/mesh/tetgen_format.h"

namespace torsion {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace vtk_format_test {

using test::failsWith;

Result<RawTetMesh> parse(const std::string& text) {
  return parseVtk(text, "m.vtk");
}

/// text with the first occurrence of `from` replaced by `to` (which must be there).
std::string with(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "'" << from << "' not in the test mesh";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// One tet; the line numbers are used by the fault tests.
const std::string kTet = R"(# vtk DataFile Version 3.0
one tet
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 float
0 0 0
1 0 0
0 1 0
0 0 1
CELLS 1 5
4 0 1 2 3
CELL_TYPES 1
10
)";

// The same tet in the 5.1 layout.
const std::string kTet51 = R"(# vtk DataFile Version 5.1
one tet
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 float
0 0 0
1 0 0
0 1 0
0 0 1
CELLS 2 4
OFFSETS vtktypeint64
0 4
CONNECTIVITY vtktypeint64
0 1 2 3
CELL_TYPES 1
10
)";

TetMesh cube() {
  Result<RawTetMesh> raw = parseTetGen(test::kCubeNode, "cube.node", test::kCubeEle, "cube.ele");
  if (!raw.ok()) {
    ADD_FAILURE() << raw.error().message;
    return TetMesh();
  }
  Result<LoadedMesh> loaded = buildTetMesh(raw.value());
  if (!loaded.ok()) {
    ADD_FAILURE() << loaded.error().message;
    return TetMesh();
  }
  return loaded.value().mesh;
}

TEST(Vtk, ReadsSingleTet) {
  Result<RawTetMesh> raw = parse(kTet);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions.size(), 4u);
  ASSERT_EQ(raw.value().tets.size(), 1u);
  EXPECT_EQ(raw.value().tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(raw.value().origins[0].line, 11);
  EXPECT_EQ(raw.value().origins[0].id, 0);
  EXPECT_EQ(raw.value().element_file, "m.vtk");
  EXPECT_TRUE(raw.value().notes.empty());
  EXPECT_TRUE(buildTetMesh(raw.value()).ok());
}

TEST(Vtk, ReadsClassicLayoutWithMixedCells) {
  const std::string text = R"(# vtk DataFile Version 4.2
cube with its surface partly written as triangles, an edge and a vertex
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 8 double
0 0 0  1 0 0  0 1 0  1 1 0
0 0 1  1 0 1  0 1 1  1 1 1
CELLS 9 38
3 0 2 1
4 0 1 2 4
4 3 2 1 7
3 0 1 4
4 5 1 4 7
4 6 4 2 7
4 1 2 4 7
2 0 7
1 5
CELL_TYPES 9
5 10 10 5 10 10 10 3 1
CELL_DATA 9
SCALARS material int 1
LOOKUP_TABLE default
0 1 1 0 1 1 1 0 0
)";
  Result<RawTetMesh> raw = parse(text);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions.size(), 8u);
  ASSERT_EQ(raw.value().tets.size(), 5u);
  EXPECT_EQ(raw.value().tets[1], (Tet{3, 2, 1, 7}));
  EXPECT_EQ(raw.value().origins[1].line, 11);  // the row of cell 2
  EXPECT_EQ(raw.value().origins[1].id, 2);
  EXPECT_EQ(raw.value().origins[2].id, 4);
  ASSERT_EQ(raw.value().notes.size(), 3u);
  EXPECT_EQ(raw.value().notes[0], "m.vtk: skipped 1 cell of type 1 (vertex)");
  EXPECT_EQ(raw.value().notes[1], "m.vtk: skipped 1 cell of type 3 (line)");
  EXPECT_EQ(raw.value().notes[2], "m.vtk: skipped 2 cells of type 5 (triangle)");
  Result<LoadedMesh> built = buildTetMesh(raw.value());
  ASSERT_TRUE(built.ok()) << built.error().message;
  EXPECT_EQ(built.value().mesh.tetCount(), 5);
  EXPECT_EQ(built.value().warnings.size(), 3u);  // the notes reach the user
}

TEST(Vtk, ReadsOffsetsConnectivityLayout) {
  const std::string text = R"(# vtk DataFile Version 5.1
vtk output
ASCII
DATASET UNSTRUCTURED_GRID
FIELD FieldData 2
TIME 1 1 double
0.5
CYCLE 1 1 int
3
POINTS 5 float
0 0 0 1 0 0 0 1 0
0 0 1 1 1 1
METADATA
INFORMATION 2
NAME L2_NORM_RANGE LOCATION vtkDataArray
DATA 2 0 1.73205
NAME L2_NORM_FINITE_RANGE LOCATION vtkDataArray
DATA 2 0 1.73205

CELLS 4 11
OFFSETS vtktypeint64
0 3 7 11
CONNECTIVITY vtktypeint64
0 1 2
0 1 2 3
1 2 3 4
CELL_TYPES 3
5
10
10

POINT_DATA 5
SCALARS t float 1
LOOKUP_TABLE default
nan 1 2 3 4
)";
  Result<RawTetMesh> raw = parse(text);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions.size(), 5u);
  EXPECT_EQ(raw.value().positions[4], Eigen::Vector3d(1, 1, 1));
  ASSERT_EQ(raw.value().tets.size(), 2u);
  EXPECT_EQ(raw.value().tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(raw.value().tets[1], (Tet{1, 2, 3, 4}));
  EXPECT_EQ(raw.value().origins[0].line, 25);  // where the cell's connectivity starts
  EXPECT_EQ(raw.value().origins[1].line, 26);
  EXPECT_EQ(raw.value().origins[1].id, 2);
  ASSERT_EQ(raw.value().notes.size(), 1u);
  EXPECT_EQ(raw.value().notes[0], "m.vtk: skipped 1 cell of type 5 (triangle)");

  Result<RawTetMesh> single = parse(kTet51);
  ASSERT_TRUE(single.ok()) << single.error().message;
  EXPECT_EQ(single.value().tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(single.value().origins[0].line, 14);
}

TEST(Vtk, ReadsNumbersSplitAcrossLinesAndLowerCaseKeywords) {
  const std::string text =
      "# vtk DataFile Version 2.0\r\n"
      "\r\n"  // a blank title
      "ascii\r\n"
      "DATASET\n"
      "unstructured_grid points\n"
      "4\n"
      "double 0 0\n"
      "0 1e0 0 0 0 +1 0 0\n"
      "\t0\n"
      "1 CELLS 1\n"
      "5 4 0 1\n"
      "2\n"
      "3 cell_types 1 10";  // no final newline
  Result<RawTetMesh> raw = parse(text);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions[1], Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(raw.value().positions[2], Eigen::Vector3d(0, 1, 0));
  EXPECT_EQ(raw.value().positions[3], Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(raw.value().tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(raw.value().origins[0].line, 11);
}

TEST(Vtk, RoundTripsThroughItsWriterWithFields) {
  const TetMesh mesh = cube();
  std::vector<Eigen::Vector3d> deformed = mesh.restPositions();
  for (Eigen::Vector3d& p : deformed)
    p = 1.1 * p + Eigen::Vector3d(0.1, -1.0 / 3.0, 1e-17);
  MeshFields fields;
  fields.node_fields.push_back({"temperature", 1, std::vector<double>(8, 0.1)});
  fields.node_fields.push_back({"displacement", 3, std::vector<double>(24, -2.5)});
  fields.tet_fields.push_back({"von_mises_Pa", 1, {1e6, 2e6, 3e6, 4e6, 5e6}});
  fields.tet_fields.push_back({"principal stress", 3, std::vector<double>(15, 1.0)});

  const std::string text = formatVtk(mesh, deformed, fields, "a title\nover two lines");
  EXPECT_EQ(text.rfind("# vtk DataFile Version 4.2\na title over two lines\nASCII\n", 0), 0u);
  EXPECT_NE(text.find("POINTS 8 double\n"), std::string::npos);
  EXPECT_NE(text.find("CELLS 5 25\n4 0 1 2 4\n"), std::string::npos);
  EXPECT_NE(text.find("CELL_TYPES 5\n10\n10\n10\n10\n10\n"), std::string::npos);
  EXPECT_NE(text.find("POINT_DATA 8\nSCALARS temperature double 1\nLOOKUP_TABLE default\n"
                      "0.10000000000000001\n"),
            std::string::npos);
  EXPECT_NE(text.find("VECTORS displacement double\n-2.5 -2.5 -2.5\n"), std::string::npos);
  EXPECT_NE(
      text.find("CELL_DATA 5\nSCALARS von_mises_Pa double 1\nLOOKUP_TABLE default\n1000000\n"),
      std::string::npos);
  EXPECT_NE(text.find("VECTORS principal_stress double\n"), std::string::npos);

  Result<RawTetMesh> again = parse(text);
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again.value().positions, deformed);  // bit for bit
  EXPECT_EQ(again.value().tets, mesh.tets());
  EXPECT_TRUE(again.value().notes.empty());

  Result<RawTetMesh> rest = parse(formatVtk(mesh, mesh.restPositions()));
  ASSERT_TRUE(rest.ok()) << rest.error().message;
  EXPECT_EQ(rest.value().positions, mesh.restPositions());
  Result<LoadedMesh> rebuilt = buildTetMesh(rest.value());
  ASSERT_TRUE(rebuilt.ok()) << rebuilt.error().message;
  EXPECT_EQ(rebuilt.value().mesh.tets(), mesh.tets());
}

// ---- one test per fault class ----

TEST(VtkFaults, MissingOrGarbledHeader) {
  EXPECT_TRUE(failsWith(parse(""), {"m.vtk:0:", "unexpected end of file", "# vtk DataFile"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "# vtk DataFile Version 3.0", "one tet")),
                        {"m.vtk:1:", "expected the header", "not a legacy VTK file"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "Version 3.0", "Version three")),
                        {"m.vtk:1:", "garbled header", "'three'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "Version 3.0", "Version")),
                        {"m.vtk:1:", "garbled header", "found nothing"}));
  EXPECT_TRUE(
      failsWith(parse("# vtk DataFile Version 3.0\n"), {"m.vtk:1:", "end of file", "title"}));
}

TEST(VtkFaults, BinaryRefused) {
  EXPECT_TRUE(failsWith(parse(with(kTet, "ASCII", "BINARY")),
                        {"m.vtk:3:", "BINARY", "not supported", "ASCII"}));
  EXPECT_TRUE(
      failsWith(parse(with(kTet, "ASCII", "XML")), {"m.vtk:3:", "'ASCII' or 'BINARY'", "'XML'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "one tet\n", "")),
                        {"m.vtk:3:", "'DATASET'", "title line missing"}));
}

TEST(VtkFaults, OtherDatasetRefused) {
  EXPECT_TRUE(failsWith(parse(with(kTet, "UNSTRUCTURED_GRID", "POLYDATA")),
                        {"m.vtk:4:", "dataset 'POLYDATA' is not supported", "UNSTRUCTURED_GRID"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "DATASET UNSTRUCTURED_GRID", "POINTS 4 float")),
                        {"m.vtk:4:", "expected 'DATASET UNSTRUCTURED_GRID'", "'POINTS'"}));
}

TEST(VtkFaults, MissingSection) {
  const std::string head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  EXPECT_TRUE(failsWith(parse(head), {"m.vtk:4:", "no POINTS section"}));
  EXPECT_TRUE(
      failsWith(parse(head + "CELLS 1 5\n4 0 1 2 3\n"), {"m.vtk:5:", "CELLS before POINTS"}));
  const std::string points = head + "POINTS 4 float\n0 0 0 1 0 0 0 1 0 0 0 1\n";
  EXPECT_TRUE(failsWith(parse(points), {"m.vtk:6:", "no CELLS section"}));
  EXPECT_TRUE(failsWith(parse(points + "POINT_DATA 4\n"), {"m.vtk:7:", "no CELLS section"}));
  EXPECT_TRUE(
      failsWith(parse(points + "CELL_TYPES 1\n10\n"), {"m.vtk:7:", "CELL_TYPES before CELLS"}));
  const std::string cells = points + "CELLS 1 5\n4 0 1 2 3\n";
  EXPECT_TRUE(failsWith(parse(cells), {"m.vtk:8:", "no CELL_TYPES section after CELLS (line 7)"}));
  EXPECT_TRUE(failsWith(parse(cells + "CELL_DATA 1\nSCALARS s float 1\n"),
                        {"m.vtk:9:", "no CELL_TYPES section"}));
}

TEST(VtkFaults, SectionRepeatedOrUnknown) {
  EXPECT_TRUE(failsWith(parse(kTet + "POINTS 1 float\n0 0 0\n"),
                        {"m.vtk:14:", "a second POINTS section", "line 5"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELL_TYPES", "VERTICES 1 2\n1 0\nCELL_TYPES")),
                        {"m.vtk:12:", "unknown section 'VERTICES'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "POINTS 4 float", "POINTS 4 string")),
                        {"m.vtk:5:", "POINTS data type 'string'", "not a numeric type"}));
}

TEST(VtkFaults, CountsDoNotMatch) {
  EXPECT_TRUE(
      failsWith(parse(with(kTet, "POINTS 4", "POINTS 5")),
                {"m.vtk:10:", "POINTS (line 5) declares 5 points, found 4 before 'CELLS'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "POINTS 4", "POINTS 3")),
                        {"m.vtk:9:", "unexpected value '0' after the POINTS section (line 5)"}));
  EXPECT_TRUE(
      failsWith(parse(with(kTet, "CELLS 1 5", "CELLS 2 10")),
                {"m.vtk:12:", "CELLS (line 10) declares 2 cells, found 1 before 'CELL_TYPES'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELLS 1 5", "CELLS 1 6")),
                        {"m.vtk:10:", "list size of 6", "1 cell uses 5"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELLS 1 5", "CELLS 1 4")),
                        {"m.vtk:11:", "cell 0: its 4 points run past the list size 4"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELL_TYPES 1", "CELL_TYPES 2")),
                        {"m.vtk:12:", "CELL_TYPES declares 2 cells, CELLS (line 10) declares 1"}));
  EXPECT_TRUE(failsWith(parse(kTet + "10\n"),
                        {"m.vtk:14:", "unexpected value '10' after the CELL_TYPES section"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELLS 1 5", "CELLS 0 0")), {"m.vtk:10:", "no cells"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "POINTS 4", "POINTS 0")), {"m.vtk:5:", "0 points"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "POINTS 4", "POINTS -4")), {"m.vtk:5:", "-4 points"}));
}

TEST(VtkFaults, OffsetsAndConnectivity) {
  EXPECT_TRUE(failsWith(parse(with(kTet51, "0 4\n", "1 4\n")),
                        {"m.vtk:12:", "the first offset must be 0, found 1"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "CELLS 2 4\nOFFSETS vtktypeint64\n0 4",
                                   "CELLS 3 4\nOFFSETS vtktypeint64\n0 4 3")),
                        {"m.vtk:12:", "offset 2 (3) is smaller than the one before it (4)"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "0 4\n", "0 5\n")),
                        {"m.vtk:12:", "offset 1 (5) is beyond the connectivity size 4"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "0 4\n", "0 3\n")),
                        {"m.vtk:12:", "the last offset is 3", "declares 4 connectivity entries"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "CONNECTIVITY vtktypeint64\n", "")),
                        {"m.vtk:13:", "expected CONNECTIVITY", "found '0'"}));
  EXPECT_TRUE(
      failsWith(parse(with(kTet51, "0 1 2 3\n", "0 1 2\n")),
                {"m.vtk:15:", "declares 4 connectivity entries, found 3 before 'CELL_TYPES'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "OFFSETS vtktypeint64", "OFFSETS float")),
                        {"m.vtk:11:", "OFFSETS data type 'float' is not an integer type"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "CELLS 2 4\nOFFSETS vtktypeint64\n0 4",
                                   "CELLS 1 0\nOFFSETS vtktypeint64\n0")),
                        {"m.vtk:10:", "holds no cells"}));
}

TEST(VtkFaults, Truncated) {
  EXPECT_TRUE(failsWith(
      parse(kTet.substr(0, kTet.find("0 1 0\n"))),
      {"m.vtk:7:", "unexpected end of file: POINTS (line 5) declares 4 points, found 2"}));
  EXPECT_TRUE(
      failsWith(parse(kTet.substr(0, kTet.find("2 3\nCELL_TYPES"))),
                {"m.vtk:11:", "unexpected end of file: CELLS (line 10) declares 1 cell, found 0"}));
  EXPECT_TRUE(failsWith(
      parse(kTet.substr(0, kTet.find("10\n", 100))),
      {"m.vtk:12:", "unexpected end of file: CELL_TYPES (line 12) declares 1 cell type"}));
  EXPECT_TRUE(failsWith(parse(kTet.substr(0, kTet.find("1 0 0\n"))),
                        {"m.vtk:6:", "unexpected end of file"}));

  // Every prefix of a valid file, cut anywhere, is a clean error naming the file and a line.
  for (const std::string& whole : {kTet, kTet51}) {
    for (size_t n = 0; n + 1 < whole.size(); ++n) {
      Result<RawTetMesh> raw = parse(whole.substr(0, n));
      if (n + 3 < whole.size()) {
        EXPECT_TRUE(failsWith(raw, {"m.vtk:"})) << "cut at " << n;
      }
    }
  }
}

TEST(VtkFaults, NonNumericToken) {
  EXPECT_TRUE(failsWith(parse(with(kTet, "1 0 0\n", "1 zero 0\n")),
                        {"m.vtk:7:", "coordinate y of point 1", "'zero'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "4 0 1 2 3", "4 0 1 2 3.5")),
                        {"m.vtk:11:", "integer", "point 3 of cell 0", "'3.5'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELL_TYPES 1\n10", "CELL_TYPES 1\ntet")),
                        {"m.vtk:13:", "integer", "type of cell 0", "'tet'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELLS 1 5", "CELLS one 5")),
                        {"m.vtk:10:", "integer", "number of cells", "'one'"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "0 4\n", "0 4x\n")), {"m.vtk:12:", "offset 1", "'4x'"}));
}

TEST(VtkFaults, NonFiniteCoordinate) {
  EXPECT_TRUE(failsWith(parse(with(kTet, "1 0 0\n", "nan 0 0\n")),
                        {"m.vtk:7:", "coordinate x of point 1 is not finite"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "0 1 0\n", "0 -inf 0\n")),
                        {"m.vtk:8:", "coordinate y of point 2 is not finite"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "0 0 1\n", "0 0 1e999\n")), {"m.vtk:9:", "out of range"}));
}

TEST(VtkFaults, PointIndexOutOfRange) {
  EXPECT_TRUE(failsWith(parse(with(kTet, "4 0 1 2 3", "4 0 1 2 4")),
                        {"m.vtk:11:", "cell 0: point 4 >= point count 4"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "4 0 1 2 3", "4 0 -1 2 3")),
                        {"m.vtk:11:", "cell 0: point -1 is negative"}));
  EXPECT_TRUE(failsWith(parse(with(kTet51, "0 1 2 3\n", "0 1\n2 912\n")),
                        {"m.vtk:15:", "cell 0: point 912 >= point count 4"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "4 0 1 2 3", "4 0 1 2 99999999999999999999")),
                        {"m.vtk:11:", "out of range"}));
}

TEST(VtkFaults, TetWithWrongPointCount) {
  EXPECT_TRUE(
      failsWith(parse(with(kTet, "CELLS 1 5\n4 0 1 2 3", "CELLS 1 4\n3 0 1 2")),
                {"m.vtk:11:", "cell 0: a tetrahedron (cell type 10) needs 4 points, found 3"}));
  EXPECT_TRUE(
      failsWith(parse(with(with(with(kTet51, "CELLS 2 4", "CELLS 2 3"), "0 4\n", "0 3\n"),
                           "0 1 2 3\n", "0 1 2\n")),
                {"m.vtk:14:", "cell 0: a tetrahedron (cell type 10) needs 4 points, found 3"}));
}

TEST(VtkFaults, NoTetrahedra) {
  EXPECT_TRUE(failsWith(
      parse(with(with(kTet, "CELLS 1 5\n4 0 1 2 3", "CELLS 2 8\n3 0 1 2\n3 0 1 3"),
                 "CELL_TYPES 1\n10", "CELL_TYPES 2\n5 5")),
      {"m.vtk:13:", "no tetrahedra (cell type 10) among 2 cells", "2 cells of type 5 (triangle)"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "CELL_TYPES 1\n10", "CELL_TYPES 1\n24")),
                        {"m.vtk:12:", "no tetrahedra", "type 24 (quadratic tetrahedron)",
                         "quadratic tetrahedra are not supported"}));
}

TEST(VtkFaults, HostileCountsFailWithoutHugeAllocations) {
  EXPECT_TRUE(failsWith(parse(with(kTet, "POINTS 4", "POINTS 9223372036854775807")),
                        {"m.vtk:5:", "at most 2147483647"}));
  EXPECT_TRUE(failsWith(parse(with(kTet, "POINTS 4", "POINTS 2000000000")),
                        {"m.vtk:10:", "declares 2000000000 points, found 4 before 'CELLS'"}));
  EXPECT_TRUE(
      failsWith(parse(with(kTet, "CELLS 1 5", "CELLS 9223372036854775807 9223372036854775807")),
                {"m.vtk:12:", "found 1 before 'CELL_TYPES'"}));
  EXPECT_TRUE(failsWith(
      parse(with(kTet, "CELLS 1 5\n4", "CELLS 1 9223372036854775807\n9223372036854775806")),
      {"m.vtk:12:", "before 'CELL_TYPES'"}));
  EXPECT_TRUE(
      failsWith(parse(with(kTet51, "CELLS 2 4", "CELLS 9223372036854775807 9223372036854775807")),
                {"m.vtk:13:", "before 'CONNECTIVITY'"}));
  EXPECT_TRUE(failsWith(
      parse(with(kTet, "DATASET UNSTRUCTURED_GRID\n",
                 "DATASET UNSTRUCTURED_GRID\nFIELD f 1\na 9223372036854775807 2 float\n")),
      {"m.vtk:6:", "too many values"}));
}

// A cheap stand-in for the fuzzer: random byte edits of valid files never crash or hang, and every
// failure names the file.
TEST(VtkFaults, RandomEditsFailCleanly) {
  std::mt19937 rng(12345);
  const std::string alphabet = "0123456789 \n-+.eE#aCELLSPOINTSnan";
  for (const std::string& whole : {kTet, kTet51}) {
    for (int round = 0; round < 3000; ++round) {
      std::string text = whole;
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        const size_t at = rng() % text.size();
        switch (rng() % 3) {
          case 0:
            text[at] = alphabet[rng() % alphabet.size()];
            break;
          case 1:
            text.erase(at, 1 + rng() % 8);
            break;
          default:
            text.insert(at, 1, alphabet[rng() % alphabet.size()]);
            break;
        }
        if (text.empty()) text = "#";
      }
      Result<RawTetMesh> raw = parse(text);
      if (!raw.ok()) {
        ASSERT_EQ(raw.error().message.rfind("m.vtk:", 0), 0u) << raw.error().message;
        continue;
      }
      ASSERT_EQ(raw.value().origins.size(), raw.value().tets.size());
      for (const Tet& tet : raw.value().tets) {
        for (int v : tet)
          ASSERT_TRUE(v >= 0 && static_cast<size_t>(v) < raw.value().positions.size());
      }
    }
  }
}

}  // namespace vtk_format_test
}  // namespace torsion
