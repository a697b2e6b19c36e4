// A scene's "bullet_file": rigid bodies that Bullet's serializer wrote, read by Bullet's own
// importer in a child process (bullet_file_import.h), in contact with the scene's FEM bodies.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "scene_builder.h"
#include "scene_parser.h"

namespace torsion::scene {
namespace {

TEST(BulletFileScene, ImportedBoxesFallOntoTheFemSlabAndRestOnIt) {
  Result<SceneSpec> spec = loadScene(std::string(TORSION_SCENES_DIR) + "/bullet_boxes.json");
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  Result<std::unique_ptr<BuiltScene>> built = buildScene(std::move(spec).value());
  ASSERT_TRUE(built.ok()) << built.error().message;
  BuiltScene& scene = *built.value();
  // The file holds a static ground and three 0.2 m boxes dropped from 0.8, 1.1 and 1.4 m.
  ASSERT_EQ(scene.rigid_bodies.size(), 4u);
  EXPECT_EQ(scene.rigid_bodies[1].name, "boxes_1");
  EXPECT_EQ(scene.world->bulletWorld().getGravity().z(), btScalar(-9.81)) << "the scene's gravity";
  // 2.5 s: the last box lands near 0.6 s and rocks a while. Where each box is at 1.5 s, to see
  // that it stays there.
  std::vector<btVector3> settled;
  std::vector<double> fastest(4, 0.0);  // m/s, each box's largest speed in the last second
  for (int k = 0; k < 250; ++k) {
    ASSERT_TRUE(driveHands(scene).ok());
    const WorldStepReport r = scene.world->step();
    ASSERT_TRUE(r.ok) << r.message;
    if (k == 149) {
      for (size_t b = 1; b < 4; ++b)
        settled.push_back(scene.rigid_bodies[b].body->getWorldTransform().getOrigin());
    }
    if (k > 149) {
      for (size_t b = 1; b < 4; ++b) {
        fastest[b] =
            std::max(fastest[b],
                     static_cast<double>(scene.rigid_bodies[b].body->getLinearVelocity().length()));
      }
    }
  }
  for (size_t b = 1; b < 4; ++b) {
    std::cout
        << "[figures] bullet_boxes box " << b << ": moved "
        << (scene.rigid_bodies[b].body->getWorldTransform().getOrigin() - settled[b - 1]).length()
        << " m in the last second, fastest " << fastest[b] << " m/s\n";
  }
  // Each box rests on the slab (top at z = 0.2 m): its centre 0.1 m above the sagging surface,
  // within the sag of this soft slab (a few mm), and it stays where it settled. Resting, the box
  // moves only with the slab's residual vibration: less than 1 mm in the last second (measured
  // 0.06-0.08 mm; before the friction's slip resistance, docs/contact.md, the boxes crept 2-7 mm
  // per second). And it does not chatter: a box that loses its support for a step falls g dt
  // = 0.098 m/s (that was the chatter: speeds jumping between 0 and 0.09 m/s from step to step);
  // its largest speed in the last second stays below a third of that (measured 0.006-0.011 m/s).
  const double free_fall_per_step = 9.81 * 0.01;
  for (size_t k = 1; k < 4; ++k) {
    const btRigidBody* box = scene.rigid_bodies[k].body;
    EXPECT_NEAR(box->getWorldTransform().getOrigin().z(), 0.3, 0.01) << "box " << k;
    EXPECT_LT((box->getWorldTransform().getOrigin() - settled[k - 1]).length(), 1e-3)
        << "box " << k;
    EXPECT_LT(fastest[k], free_fall_per_step / 3) << "box " << k;
  }
}

TEST(BulletFileScene, AFileBulletCannotReadIsAnErrorNamingTheKey) {
  const std::string text =
      R"({"bodies": [{"name": "slab", "mesh": ")" + std::string(TORSION_ASSETS_DIR) +
      R"(/slab_768.node", "material": {"youngs_modulus": 5e4, "poisson_ratio": 0.3, "density": 300}}],
      "bullet_file": ")" +
      std::string(TORSION_ASSETS_DIR) + R"(/slab_768.node"})";
  Result<SceneSpec> spec = parseScene(text, "b.json", "/base");
  ASSERT_FALSE(spec.ok());
  EXPECT_NE(spec.error().message.find("b.json: bullet_file: "), std::string::npos)
      << spec.error().message;
  EXPECT_NE(spec.error().message.find("slab_768.node: not a file Bullet's serializer wrote"),
            std::string::npos)
      << spec.error().message;
}

TEST(BulletFileScene, AMissingFileIsAnErrorNamingIt) {
  const std::string text =
      R"({"bodies": [{"name": "slab", "mesh": ")" + std::string(TORSION_ASSETS_DIR) +
      R"(/slab_768.node", "material": {"youngs_modulus": 5e4, "poisson_ratio": 0.3, "density": 300}}],
      "bullet_file": "nowhere.bullet"})";
  Result<SceneSpec> spec = parseScene(text, "b.json", "/base");
  ASSERT_FALSE(spec.ok());
  EXPECT_NE(spec.error().message.find("/base/nowhere.bullet"), std::string::npos)
      << spec.error().message;
}

}  // namespace
}  // namespace torsion::scene
