// The material key "volumetric_strain" (element | nodal_average, default element): nodal-average
// volumetric strain for nearly incompressible tet4 bodies (fem/nodal_pressure.h).
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace volumetric_strain_key_test {

std::string sceneWith(const std::string& material_entry, const std::string& body_entry = "") {
  return R"({"bodies": [{"name": "beam", "mesh": "beam.node",)" + body_entry +
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.49, "density": 1000)" +
         material_entry + "}}]}";
}

TEST(SceneVolumetricStrainKey, DefaultsToPerElementAndReadsNodalAverage) {
  Result<SceneSpec> plain = parseScene(sceneWith(""), "s.json", "/base");
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().bodies[0].material.volumetric_strain, VolumetricStrain::kPerElement);
  Result<SceneSpec> nodal =
      parseScene(sceneWith(R"(, "volumetric_strain": "nodal_average")"), "s.json", "/base");
  ASSERT_TRUE(nodal.ok()) << nodal.error().message;
  EXPECT_EQ(nodal.value().bodies[0].material.volumetric_strain, VolumetricStrain::kNodalAverage);
}

TEST(SceneVolumetricStrainKey, UnknownValueAndTet10AreRefusedNamingTheKey) {
  EXPECT_TRUE(
      test::failsWith(parseScene(sceneWith(R"(, "volumetric_strain": "fbar")"), "s.json", "/base"),
                      {"s.json: bodies[0].material.volumetric_strain",
                       "'fbar' is not a volumetric strain (element or nodal_average)"}));
  EXPECT_TRUE(test::failsWith(
      parseScene(sceneWith(R"(, "volumetric_strain": "nodal_average")", R"( "element": "tet10",)"),
                 "s.json", "/base"),
      {"s.json: bodies[0].material", "tet4 option"}));
}

}  // namespace volumetric_strain_key_test
}  // namespace torsion::scene
