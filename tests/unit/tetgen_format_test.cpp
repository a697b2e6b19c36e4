#include "torsion/mesh/tetgen_format.h"

#include <gtest/gtest.h>

#include "error_matchers.h"
#include "test_meshes.h"
#include "torsion/mesh/tet_mesh_builder.h"

namespace torsion {
namespace {

using test::failsWith;

Result<RawTetMesh> parse(const std::string& node, const std::string& ele) {
  return parseTetGen(node, "m.node", ele, "m.ele");
}

const std::string kTetNode = "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n";
const std::string kTetEle = "1 4 0\n0 0 1 2 3\n";

TEST(TetGen, ReadsZeroBasedCube) {
  Result<RawTetMesh> raw = parse(test::kCubeNode, test::kCubeEle);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions.size(), 8u);
  ASSERT_EQ(raw.value().tets.size(), 5u);
  EXPECT_EQ(raw.value().tets[1], (Tet{3, 2, 1, 7}));
  EXPECT_EQ(raw.value().origins[1].line, 3);  // line 1 is the header
  EXPECT_EQ(raw.value().positions[7], Eigen::Vector3d(1, 1, 1));
}

TEST(TetGen, ReadsOneBasedWithAttributesMarkersAndComments) {
  const std::string node =
      "# made by hand\n"
      "4 3 1 1   # one attribute, markers\n"
      "\n"
      "1 0 0 0  7.5 1\n"
      "2 1 0 0  7.5 1  # trailing comment\n"
      "3 0 1 0  7.5 0\n"
      "4 0 0 1  7.5 1\n";
  const std::string ele = "1 4 1\n1 1 2 3 4 42\n";
  Result<RawTetMesh> raw = parse(node, ele);
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().tets[0], (Tet{0, 1, 2, 3}));
  EXPECT_EQ(raw.value().origins[0].id, 1);
}

TEST(TetGen, ReadsAByteOrderMarkAndWindowsLineEndings) {
  // Editors on Windows save "\xEF\xBB\xBF" first and end lines in CR LF.
  auto windows = [](const std::string& text) {
    std::string out = "\xEF\xBB\xBF";
    for (char c : text)
      out += c == '\n' ? std::string("\r\n") : std::string(1, c);
    return out;
  };
  Result<RawTetMesh> raw = parse(windows(test::kCubeNode), windows(test::kCubeEle));
  ASSERT_TRUE(raw.ok()) << raw.error().message;
  EXPECT_EQ(raw.value().positions.size(), 8u);
  EXPECT_EQ(raw.value().tets.size(), 5u);
  EXPECT_EQ(raw.value().positions[7], Eigen::Vector3d(1, 1, 1));
}

TEST(TetGen, RoundTripsThroughItsWriter) {
  Result<LoadedMesh> first = buildTetMesh(parse(test::kCubeNode, test::kCubeEle).value());
  ASSERT_TRUE(first.ok());
  const TetGenText text = formatTetGen(first.value().mesh);
  Result<RawTetMesh> again = parse(text.node, text.ele);
  ASSERT_TRUE(again.ok()) << again.error().message;
  EXPECT_EQ(again.value().positions, first.value().mesh.restPositions());
  EXPECT_EQ(again.value().tets, first.value().mesh.tets());
}

// ---- one test per fault class ----

TEST(TetGenFaults, EmptyNodeFile) {
  EXPECT_TRUE(failsWith(parse("", kTetEle), {"m.node:0:", "unexpected end of file"}));
  EXPECT_TRUE(failsWith(parse("# only a comment\n", kTetEle), {"m.node:1:", "end of file"}));
}

TEST(TetGenFaults, EmptyEleFile) {
  EXPECT_TRUE(failsWith(parse(kTetNode, "\n\n"), {"m.ele:2:", "unexpected end of file"}));
}

TEST(TetGenFaults, UnsupportedHeader) {
  EXPECT_TRUE(failsWith(parse("4 2 0 0\n", kTetEle), {"m.node:1:", "dimension is 2"}));
  EXPECT_TRUE(
      failsWith(parse(kTetNode, "1 10 0\n0 0 1 2 3 4 5 6 7 8 9\n"), {"m.ele:1:", "10-node"}));
  EXPECT_TRUE(failsWith(parse("4 3 0 2\n", kTetEle), {"m.node:1:", "boundary markers"}));
}

TEST(TetGenFaults, CountsDoNotMatch) {
  EXPECT_TRUE(failsWith(parse("5 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n", kTetEle),
                        {"m.node:5:", "declares 5 points, found 4"}));
  EXPECT_TRUE(failsWith(parse(kTetNode + "4 1 1 1\n", kTetEle), {"m.node:6:", "more point lines"}));
  EXPECT_TRUE(failsWith(parse(kTetNode, "2 4 0\n0 0 1 2 3\n"),
                        {"m.ele:2:", "declares 2 tetrahedra, found 1"}));
}

TEST(TetGenFaults, TruncatedLine) {
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n0 0 0 0\n1 1 0\n2 0 1 0\n3 0 0 1\n", kTetEle),
                        {"m.node:3:", "4 fields", "found 3 fields"}));
  EXPECT_TRUE(failsWith(parse(kTetNode, "1 4 0\n0 0 1 2\n"), {"m.ele:2:", "found 4 fields"}));
}

TEST(TetGenFaults, NonNumericField) {
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n0 0 0 0\n1 1 zero 0\n2 0 1 0\n3 0 0 1\n", kTetEle),
                        {"m.node:3:", "coordinate y of point 1", "'zero'"}));
  EXPECT_TRUE(failsWith(parse(kTetNode, "1 4 0\n0 0 1 2 3.5\n"), {"m.ele:2:", "integer", "'3.5'"}));
}

TEST(TetGenFaults, NonFiniteCoordinate) {
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n0 0 0 0\n1 nan 0 0\n2 0 1 0\n3 0 0 1\n", kTetEle),
                        {"m.node:3:", "not finite"}));
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 inf 0\n3 0 0 1\n", kTetEle),
                        {"m.node:4:", "not finite"}));
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n0 0 0 0\n1 1e999 0 0\n2 0 1 0\n3 0 0 1\n", kTetEle),
                        {"m.node:3:", "out of range"}));
}

TEST(TetGenFaults, IndexOutOfRange) {
  EXPECT_TRUE(failsWith(parse(kTetNode, "1 4 0\n0 0 1 2 4\n"),
                        {"m.ele:2:", "tet 0: vertex 4 >= vertex count 4"}));
  EXPECT_TRUE(failsWith(parse(kTetNode, "1 4 0\n0 0 -1 2 3\n"), {"m.ele:2:", "vertex -1"}));
}

TEST(TetGenFaults, IndicesOutOfSequence) {
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n0 0 0 0\n2 1 0 0\n2 0 1 0\n3 0 0 1\n", kTetEle),
                        {"m.node:3:", "out of sequence"}));
  EXPECT_TRUE(failsWith(parse("4 3 0 0\n5 0 0 0\n", kTetEle), {"m.node:2:", "0 or 1"}));
}

}  // namespace
}  // namespace torsion

namespace torsion {
namespace {

// Inputs the fuzzer found: each must fail cleanly (no huge allocation, no overflow).
TEST(TetGenFaults, HostileHeadersAndIndices) {
  EXPECT_FALSE(
      parseTetGen("21474836481 3 0 0\n0 0 0 0\n", "m.node", "1 4 0\n0 0 1 2 3\n", "m.ele").ok());
  EXPECT_TRUE(test::failsWith(parseTetGen("4 3 9223372036854775800 1\n", "m.node", "", "m.ele"),
                              {"m.node:1:", "attributes"}));
  const std::string node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
  EXPECT_TRUE(
      test::failsWith(parseTetGen(node, "m.node", "1 4 0\n9223372036854775807 1 2 3 4\n", "m.ele"),
                      {"m.ele:2:", "first tet index must be 0 or 1"}));
  EXPECT_TRUE(
      test::failsWith(parseTetGen(node, "m.node", "1 4 0\n1 -9223372036854775808 2 3 4\n", "m.ele"),
                      {"m.ele:2:", "< first point index 1"}));
}

TEST(TetGenFaults, HugeCoordinatesOverflowingTheVolume) {
  Result<RawTetMesh> raw = parseTetGen("4 3 0 0\n0 0 0 0\n1 1e200 0 0\n2 0 1e200 0\n3 0 0 1e200\n",
                                       "m.node", "1 4 0\n0 0 1 2 3\n", "m.ele");
  ASSERT_TRUE(raw.ok());
  EXPECT_TRUE(
      test::failsWith(buildTetMesh(std::move(raw).value()), {"m.ele:2: tet 0:", "overflows"}));
}

}  // namespace
}  // namespace torsion
