// The scene's optional "camera" entry: defaults, values, and one bad input per key, each error
// naming the file and the key path.
#include "camera_spec.h"

#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_parser.h"

namespace torsion::scene {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace camera_spec_test {

using test::failsWith;

std::string sceneWith(const std::string& camera) {
  return R"({"gravity": [0, 0, 0], "bodies": [{"name": "b", "mesh": "b.node",
     "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}])" +
         (camera.empty() ? std::string() : ", \"camera\": " + camera) + "}";
}

Result<SceneSpec> parse(const std::string& camera) {
  return parseScene(sceneWith(camera), "s.json", "/base");
}

TEST(CameraSpec, AbsentMeansFitted) {
  const Result<SceneSpec> s = parse("");
  ASSERT_TRUE(s.ok()) << s.error().message;
  EXPECT_FALSE(s.value().camera.up.has_value());
  EXPECT_FALSE(s.value().camera.yaw.has_value());
  EXPECT_FALSE(s.value().camera.pitch.has_value());
  EXPECT_EQ(s.value().camera.zoom, 1.0);
}

TEST(CameraSpec, ValuesAreRead) {
  const Result<SceneSpec> s = parse(R"({"up": [0, 0, 2], "yaw": -0.9, "pitch": 0.3, "zoom": 1.5})");
  ASSERT_TRUE(s.ok()) << s.error().message;
  const CameraSpec& c = s.value().camera;
  ASSERT_TRUE(c.up.has_value());
  EXPECT_EQ(*c.up, Eigen::Vector3d(0, 0, 1));  // normalised
  EXPECT_EQ(*c.yaw, -0.9);
  EXPECT_EQ(*c.pitch, 0.3);
  EXPECT_EQ(c.zoom, 1.5);
}

TEST(CameraSpec, BadValuesNameTheKey) {
  EXPECT_TRUE(failsWith(parse(R"({"up": [0, 0, 0]})"), {"s.json: camera.up: must be a non-zero"}));
  EXPECT_TRUE(
      failsWith(parse(R"({"pitch": 1.6})"), {"s.json: camera.pitch: must be in (-1.5, 1.5)"}));
  EXPECT_TRUE(failsWith(parse(R"({"zoom": 0})"), {"s.json: camera.zoom: must be > 0"}));
  EXPECT_TRUE(failsWith(parse(R"({"yaw": "left"})"), {"s.json: camera.yaw: expected a number"}));
  EXPECT_TRUE(failsWith(parse(R"({"distance": 3})"), {"s.json: camera", "distance"}));
}

}  // namespace camera_spec_test
}  // namespace torsion::scene
