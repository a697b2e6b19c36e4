// The body key "node_order" (cache_friendly | file, default cache_friendly): which numbering a
// body made from the scene's mesh uses inside (torsion/mesh/input_numbering.h).
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

std::string sceneWithNodeOrder(const std::string& entry) {
  return R"({"bodies": [{"name": "cyl", "mesh": "cyl.node",)" + entry +
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}]})";
}

TEST(SceneNodeOrderKey, DefaultsToCacheFriendlyAndReadsFile) {
  Result<SceneSpec> plain = parseScene(sceneWithNodeOrder(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].numbering, NodeNumbering::kCacheFriendly);
  Result<SceneSpec> file =
      parseScene(sceneWithNodeOrder(R"( "node_order": "file",)"), "s.json", "/base");
  ASSERT_TRUE(file.ok()) << file.error().message;
  EXPECT_EQ(file.value().bodies[0].numbering, NodeNumbering::kAsGiven);
}

TEST(SceneNodeOrderKey, UnknownOrderOrWrongTypeNamesTheKey) {
  EXPECT_TRUE(test::failsWith(
      parseScene(sceneWithNodeOrder(R"( "node_order": "rcm",)"), "s.json", "/base"),
      {"s.json: bodies[0].node_order", "'rcm' is not a node order (cache_friendly or file)"}));
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWithNodeOrder(R"( "node_order": 1,)"), "s.json", "/base"),
                      {"s.json: bodies[0].node_order", "string"}));
}

}  // namespace
}  // namespace torsion::scene
