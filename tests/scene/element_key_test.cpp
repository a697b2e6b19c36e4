// The body keys "element" (tet4 | tet10, default tet4) and "node_order" (cache_friendly | file,
// default cache_friendly: the numbering a body made from the scene's mesh uses inside,
// torsion/mesh/input_numbering.h): their own file so the main parser test stays as it is.
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

std::string sceneWithBodyEntry(const std::string& entry) {
  return R"({"bodies": [{"name": "cyl", "mesh": "cyl.node",)" + entry +
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}]})";
}

TEST(SceneElementKey, DefaultsToTet4AndReadsTet10) {
  Result<SceneSpec> plain = parseScene(sceneWithBodyEntry(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].element, ElementKind::kTet4);
  Result<SceneSpec> quadratic =
      parseScene(sceneWithBodyEntry(R"( "element": "tet10",)"), "s.json", "/base");
  ASSERT_TRUE(quadratic.ok()) << quadratic.error().message;
  EXPECT_EQ(quadratic.value().bodies[0].element, ElementKind::kTet10);
}

TEST(SceneElementKey, UnknownKindOrWrongTypeNamesTheKey) {
  EXPECT_TRUE(test::failsWith(
      parseScene(sceneWithBodyEntry(R"( "element": "tet20",)"), "s.json", "/base"),
      {"s.json: bodies[0].element", "'tet20' is not an element kind (tet4 or tet10)"}));
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWithBodyEntry(R"( "element": 10,)"), "s.json", "/base"),
                      {"s.json: bodies[0].element", "string"}));
}

TEST(SceneNodeOrderKey, DefaultsToCacheFriendlyAndReadsFile) {
  Result<SceneSpec> plain = parseScene(sceneWithBodyEntry(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].numbering, NodeNumbering::kCacheFriendly);
  Result<SceneSpec> file =
      parseScene(sceneWithBodyEntry(R"( "node_order": "file",)"), "s.json", "/base");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_EQ(file.value().bodies[0].numbering, NodeNumbering::kAsGiven);
}

TEST(SceneNodeOrderKey, UnknownOrderOrWrongTypeNamesTheKey) {
  EXPECT_TRUE(test::failsWith(
      parseScene(sceneWithBodyEntry(R"( "node_order": "rcm",)"), "s.json", "/base"),
      {"s.json: bodies[0].node_order", "'rcm' is not a node order (cache_friendly or file)"}));
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWithBodyEntry(R"( "node_order": 1,)"), "s.json", "/base"),
                      {"s.json: bodies[0].node_order", "string"}));
}

}  // namespace
}  // namespace torsion::scene
