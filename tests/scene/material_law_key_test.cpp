// The material keys "law" (corotated | stable_neo_hookean | mooney_rivlin, default corotated) and
// "mooney_rivlin_c2_fraction" (docs/materials.md, docs/scene-format.md).
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

std::string sceneWithLaw(const std::string& material_entry, const std::string& body_entry = "") {
  return R"({"bodies": [{"name": "beam", "mesh": "beam.node",)" + body_entry +
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.45, "density": 1000)" +
         material_entry + "}}]}";
}

TEST(SceneMaterialLawKey, DefaultsToCorotatedAndReadsTheHyperelasticLaws) {
  Result<SceneSpec> plain = parseScene(sceneWithLaw(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].material.law, MaterialLaw::kCorotated);
  Result<SceneSpec> neo =
      parseScene(sceneWithLaw(R"(, "law": "stable_neo_hookean")"), "s.json", "/base");
  ASSERT_TRUE(neo.ok()) << neo.error().message;
  EXPECT_EQ(neo.value().bodies[0].material.law, MaterialLaw::kStableNeoHookean);
  Result<SceneSpec> mooney =
      parseScene(sceneWithLaw(R"(, "law": "mooney_rivlin", "mooney_rivlin_c2_fraction": 0.25)"),
                 "s.json", "/base");
  ASSERT_TRUE(mooney.ok()) << mooney.error().message;
  EXPECT_EQ(mooney.value().bodies[0].material.law, MaterialLaw::kMooneyRivlin);
  EXPECT_EQ(mooney.value().bodies[0].material.mooney_rivlin_c2_fraction, 0.25);
}

TEST(SceneMaterialLawKey, BadValuesAndUnsupportedCombinationsAreRefusedNamingTheKey) {
  EXPECT_TRUE(test::failsWith(parseScene(sceneWithLaw(R"(, "law": "neo")"), "s.json", "/base"),
                              {"s.json: bodies[0].material.law", "'neo' is not a material law"}));
  EXPECT_TRUE(test::failsWith(
      parseScene(sceneWithLaw(R"(, "law": "mooney_rivlin", "mooney_rivlin_c2_fraction": 1.5)"),
                 "s.json", "/base"),
      {"s.json: bodies[0].material", "mooney_rivlin_c2_fraction", "must be in [0, 1]"}));
  EXPECT_TRUE(test::failsWith(parseScene(sceneWithLaw(R"(, "law": 3)"), "s.json", "/base"),
                              {"s.json: bodies[0].material.law"}));
  EXPECT_TRUE(test::failsWith(
      parseScene(
          sceneWithLaw(R"(, "law": "stable_neo_hookean", "volumetric_strain": "nodal_average")"),
          "s.json", "/base"),
      {"s.json: bodies[0].material.volumetric_strain", "corotated option"}));
}

TEST(SceneMaterialLawKey, HyperelasticLawsRunOnQuadraticTets) {
  Result<SceneSpec> tet10 = parseScene(
      sceneWithLaw(R"(, "law": "mooney_rivlin")", R"( "element": "tet10",)"), "s.json", "/base");
  ASSERT_TRUE(tet10.ok()) << tet10.error().message;
  EXPECT_EQ(tet10.value().bodies[0].element, ElementKind::kTet10);
  EXPECT_EQ(tet10.value().bodies[0].material.law, MaterialLaw::kMooneyRivlin);
}

}  // namespace
}  // namespace torsion::scene
