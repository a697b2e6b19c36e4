// The body key "element" (tet4 | tet10, default tet4): its own file so the main parser test
// stays as it is.
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

std::string sceneWithElement(const std::string& element_entry) {
  return R"({"bodies": [{"name": "cyl", "mesh": "cyl.node",)" + element_entry +
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}]})";
}

TEST(SceneElementKey, DefaultsToTet4AndReadsTet10) {
  Result<SceneSpec> plain = parseScene(sceneWithElement(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].element, ElementKind::kTet4);
  Result<SceneSpec> quadratic =
      parseScene(sceneWithElement(R"( "element": "tet10",)"), "s.json", "/base");
  ASSERT_TRUE(quadratic.ok()) << quadratic.error().message;
  EXPECT_EQ(quadratic.value().bodies[0].element, ElementKind::kTet10);
}

TEST(SceneElementKey, UnknownKindOrWrongTypeNamesTheKey) {
  EXPECT_TRUE(test::failsWith(
      parseScene(sceneWithElement(R"( "element": "tet20",)"), "s.json", "/base"),
      {"s.json: bodies[0].element", "'tet20' is not an element kind (tet4 or tet10)"}));
  EXPECT_TRUE(test::failsWith(parseScene(sceneWithElement(R"( "element": 10,)"), "s.json", "/base"),
                              {"s.json: bodies[0].element", "string"}));
}

}  // namespace
}  // namespace torsion::scene
