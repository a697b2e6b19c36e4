// Placements and masses the step's arithmetic cannot carry (arithmetic_bounds.h), found by
// hostile scenes written by hand alongside the scene fuzzer (tests/fuzz/fuzz_scene.cpp): a body
// placed 1e300 m away, a ground 1e300 m up, a rigid body of 1e300 or 1e-300 kg used to load and
// fail in the first step with a non-finite state, blamed on "a degenerate tet?" or on an unnamed
// rigid body '#1'. Now each is refused at load naming its key, and values at the bounds still load
// and step to a finite state.
#include <gtest/gtest.h>

#include <string>

#include "../unit/error_matchers.h"
#include "arithmetic_bounds.h"
#include "scene_builder.h"
#include "scene_parser.h"
#include "torsion/format_number.h"

namespace torsion::scene {
namespace {

using test::failsWith;

std::string scene(const std::string& body_pose, const std::string& extra) {
  return R"({"bodies": [{"name": "block", "mesh": ")" + std::string(TORSION_ASSETS_DIR) +
         R"(/block_162.node", "material": {"youngs_modulus": 5e4, "poisson_ratio": 0.3,
         "density": 300}, "pose": {"position": )" +
         body_pose + "}}]" + extra + "}";
}

Result<SceneSpec> parse(const std::string& text) {
  return parseScene(text, "p.json", "/base");
}

std::string sphere(const std::string& mass) {
  return R"(, "rigid_bodies": [{"name": "ball", "shape": {"sphere": {"radius": 0.1}},
             "mass": )" +
         mass + R"(, "pose": {"position": [0, 0, 2]}}])";
}

TEST(PlacementBounds, FarBodiesGroundsAndExtremeMassesAreRefusedNamingTheKey) {
  EXPECT_TRUE(failsWith(parse(scene("[1e300, 0, 0]", "")),
                        {"p.json", "bodies[0].pose.position", "1e+300 m", "bound 1e+06 m"}));
  EXPECT_TRUE(failsWith(parse(scene("[0, 0, 0]", R"(, "ground": {"height": -1e300})")),
                        {"p.json", "ground.height", "-1e+300 m", "bound 1e+06 m"}));
  EXPECT_TRUE(failsWith(parse(scene("[0, 0, 0]", sphere("1e300"))),
                        {"p.json", "rigid_bodies[0].mass", "1e+300 kg", "outside [1e-09, 1e+12]"}));
  EXPECT_TRUE(failsWith(parse(scene("[0, 0, 0]", sphere("1e-300"))),
                        {"p.json", "rigid_bodies[0].mass", "1e-300 kg"}));
  const std::string far_ball = R"(, "rigid_bodies": [{"name": "ball", "shape": {"sphere":
      {"radius": 0.1}}, "mass": 1, "pose": {"position": [0, -2e6, 0]}}])";
  EXPECT_TRUE(failsWith(parse(scene("[0, 0, 0]", far_ball)),
                        {"p.json", "rigid_bodies[0].pose.position", "2e+06 m"}));
}

TEST(PlacementBounds, ValuesAtTheBoundsLoadAndStepToAFiniteState) {
  const std::string at_bounds = scene("[1e6, 0, 0]", R"(, "ground": {"height": -1e6},
      "rigid_bodies": [{"name": "heavy", "shape": {"sphere": {"radius": 0.1}}, "mass": 1e12,
      "pose": {"position": [-1e6, 0, 0]}}, {"name": "light", "shape": {"sphere":
      {"radius": 0.1}}, "mass": 1e-9, "pose": {"position": [0, 1e6, 0]}}])");
  Result<SceneSpec> spec = parse(at_bounds);
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  auto built = buildScene(std::move(spec).value(), BuildOptions{1});
  ASSERT_TRUE(built.ok()) << built.error().message;
  BuiltScene& s = *built.value();
  for (int k = 0; k < 3; ++k) {
    const WorldStepReport report = s.world->step();
    ASSERT_TRUE(report.ok) << report.message;
  }
  EXPECT_TRUE(s.world->bodies().front()->state().positions.allFinite());
  // Far from the origin the block still falls under gravity: 3 steps of 0.01 s from rest move
  // it down by about g t^2 / 2 (implicit Euler: a little more), resolved at 1e6 m.
  const double z = s.world->bodies().front()->state().positions[2];
  const double z0 = s.world->bodies().front()->model().mesh().restPositions()[0].z();
  EXPECT_LT(z, z0 - 1e-3);
  for (const btRigidBody* body : s.world->rigidBodies())
    EXPECT_TRUE(std::isfinite(static_cast<double>(body->getLinearVelocity().z())));
}

}  // namespace
}  // namespace torsion::scene
