// The body key "friction_solve" (auto | active_set | contact_space, default auto): how the body's
// contacts with rigid bodies decide stick and slide (docs/contact.md, "Coulomb's law solved in
// contact space"). Parsed, rejected with the key named, and carried onto the built body.
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_builder.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

std::string sceneWith(const std::string& entry) {
  return R"({"bodies": [{"name": "block", "mesh": ")" + std::string(TORSION_ASSETS_DIR) +
         R"(/block_162.node",)" + entry +
         R"( "material": {"youngs_modulus": 5e4, "poisson_ratio": 0.3, "density": 300}}]})";
}

TEST(SceneFrictionSolveKey, DefaultsToConvexAndReadsEachSolve) {
  Result<SceneSpec> plain = parseScene(sceneWith(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].friction_solve, ContactSettings::FrictionSolve::kConvex);
  for (const auto& [name, expected] :
       {std::pair{"auto", ContactSettings::FrictionSolve::kAuto},
        std::pair{"active_set", ContactSettings::FrictionSolve::kActiveSet},
        std::pair{"contact_space", ContactSettings::FrictionSolve::kContactSpace},
        std::pair{"convex", ContactSettings::FrictionSolve::kConvex}}) {
    Result<SceneSpec> spec = parseScene(
        sceneWith(" \"friction_solve\": \"" + std::string(name) + "\","), "s.json", "/base");
    ASSERT_TRUE(spec.ok()) << spec.error().message;
    EXPECT_EQ(spec.value().bodies[0].friction_solve, expected) << name;
  }
}

TEST(SceneFrictionSolveKey, AnUnknownSolveOrWrongTypeNamesTheKey) {
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWith(R"( "friction_solve": "exact",)"), "s.json", "/base"),
                      {"s.json: bodies[0].friction_solve",
                       "'exact' is not a friction solve (auto, active_set, contact_space or "
                       "convex)"}));
  EXPECT_TRUE(test::failsWith(parseScene(sceneWith(R"( "friction_solve": 1,)"), "s.json", "/base"),
                              {"s.json: bodies[0].friction_solve", "string"}));
}

TEST(SceneFrictionSolveKey, TheBuiltBodyUsesTheSolveTheSceneNames) {
  for (const auto& [entry, expected] :
       {std::pair{std::string(), ContactSettings::FrictionSolve::kConvex},
        std::pair{std::string(R"( "friction_solve": "auto",)"),
                  ContactSettings::FrictionSolve::kAuto},
        std::pair{std::string(R"( "friction_solve": "contact_space",)"),
                  ContactSettings::FrictionSolve::kContactSpace},
        std::pair{std::string(R"( "friction_solve": "active_set",)"),
                  ContactSettings::FrictionSolve::kActiveSet}}) {
    Result<SceneSpec> spec = parseScene(sceneWith(entry), "s.json", "/base");
    ASSERT_TRUE(spec.ok()) << spec.error().message;
    Result<std::unique_ptr<BuiltScene>> built = buildScene(spec.value());
    ASSERT_TRUE(built.ok()) << built.error().message;
    EXPECT_EQ(built.value()->world->body("block")->contacts().settings().friction_solve, expected);
  }
}

}  // namespace
}  // namespace torsion::scene
