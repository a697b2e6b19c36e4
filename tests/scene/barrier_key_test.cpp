// The material keys "barrier_threshold" and "barrier_stiffness" of the volume barrier against
// inverted tets (fem/volume_barrier.h; defaults 0.3 and 30 bulk moduli, threshold 0 turns it off).
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace barrier_key_test {

std::string sceneWith(const std::string& material_entry) {
  return R"({"bodies": [{"name": "beam", "mesh": "beam.node",)"
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000)" +
         material_entry + "}}]}";
}

TEST(SceneBarrierKeys, DefaultToTheMaterialsAndReadBothKeys) {
  Result<SceneSpec> plain = parseScene(sceneWith(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].material.barrier_threshold, Material{}.barrier_threshold);
  EXPECT_EQ(plain.value().bodies[0].material.barrier_stiffness, Material{}.barrier_stiffness);
  Result<SceneSpec> set = parseScene(
      sceneWith(R"(, "barrier_threshold": 0, "barrier_stiffness": 5)"), "s.json", "/base");
  ASSERT_TRUE(set.ok()) << set.error().message;
  EXPECT_EQ(set.value().bodies[0].material.barrier_threshold, 0.0);
  EXPECT_EQ(set.value().bodies[0].material.barrier_stiffness, 5.0);
}

TEST(SceneBarrierKeys, OutOfRangeValuesAreRefusedNamingTheField) {
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWith(R"(, "barrier_threshold": 1)"), "s.json", "/base"),
                      {"s.json: bodies[0].material", "barrier_threshold = 1: must be in [0, 1)"}));
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWith(R"(, "barrier_stiffness": -2)"), "s.json", "/base"),
                      {"s.json: bodies[0].material", "barrier_stiffness = -2: must be >= 0"}));
}

}  // namespace barrier_key_test
}  // namespace torsion::scene
