// Rigid bodies in scene files (docs/scene-format.md, rigid_bodies[] and ground): every shape, the
// kinematic script, and the faults, each naming the key; then a built scene whose kinematic plate
// follows its script and whose run writes rigid.csv and the contact figures.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "../unit/error_matchers.h"
#include "scene_builder.h"
#include "scene_parser.h"
#include "scene_runner.h"
#include "torsion/bt_conversions.h"

namespace torsion::scene {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace rigid_scene_test {

using test::failsWith;

std::string scene(const std::string& rigid, const std::string& extra = "") {
  return R"({"bodies": [{"name": "block", "mesh": ")" + std::string(TORSION_ASSETS_DIR) +
         R"(/block_162.node", "material": {"youngs_modulus": 5e4, "poisson_ratio": 0.3,
         "density": 300}}], "rigid_bodies": [)" +
         rigid + "]" + extra + "}";
}

Result<SceneSpec> parse(const std::string& text) {
  return parseScene(text, "r.json", "/base");
}

TEST(RigidScene, ReadsEveryShapeAndKind) {
  const std::string rigid = R"(
    {"name": "crate", "shape": {"box": {"half_extents": [0.1, 0.2, 0.3]}}, "mass": 2,
     "linear_velocity": [1, 0, 0], "angular_velocity": [0, 0, 3], "friction": 0.3,
     "restitution": 0.2},
    {"name": "ball", "shape": {"sphere": {"radius": 0.1}}},
    {"name": "pin", "shape": {"capsule": {"radius": 0.05, "half_height": 0.2, "axis": "x"}}},
    {"name": "hull", "shape": {"convex_hull": {"points": [[0,0,0],[1,0,0],[0,1,0],[0,0,1]],
     "margin": 0.002}}},
    {"name": "wall", "shape": {"plane": {"normal": [1, 0, 0], "offset": -2}}},
    {"name": "ramp", "shape": {"triangle_mesh": {"vertices": [[0,0,0],[1,0,0],[0,1,0]],
     "triangles": [[0, 1, 2]]}}},
    {"name": "plate", "shape": {"box": {"half_extents": [0.3, 0.3, 0.05]}},
     "pose": {"position": [0, 0, 1]},
     "kinematic": [{"linear_velocity": [0, 0, -0.1], "duration": 2},
                   {"angular_velocity": [0, 0, 1], "start": 1}]})";
  Result<SceneSpec> r = parse(scene(rigid, R"(, "ground": {"height": -0.5, "friction": 0.9})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const std::vector<RigidBodySpec>& b = r.value().rigid_bodies;
  ASSERT_EQ(b.size(), 7u);
  EXPECT_EQ(b[0].shape, RigidBodySpec::Shape::kBox);
  EXPECT_EQ(b[0].mass, 2);
  EXPECT_EQ(b[0].linear_velocity, Eigen::Vector3d(1, 0, 0));
  EXPECT_EQ(b[0].angular_velocity, Eigen::Vector3d(0, 0, 3));
  EXPECT_DOUBLE_EQ(b[0].friction, 0.3);
  EXPECT_DOUBLE_EQ(b[0].restitution, 0.2);
  EXPECT_EQ(b[1].mass, 1);  // dynamic by default
  EXPECT_EQ(b[2].shape, RigidBodySpec::Shape::kCapsule);
  EXPECT_EQ(b[2].axis, 0);
  EXPECT_EQ(b[3].points.size(), 4u);
  EXPECT_DOUBLE_EQ(b[3].margin, 0.002);
  EXPECT_EQ(b[4].mass, 0);  // planes and meshes are static
  EXPECT_EQ(b[5].triangles.size(), 1u);
  EXPECT_TRUE(b[6].isKinematic());
  EXPECT_EQ(b[6].mass, 0);
  ASSERT_TRUE(r.value().ground.has_value());
  EXPECT_DOUBLE_EQ(r.value().ground->plane_offset, -0.5);
  EXPECT_DOUBLE_EQ(r.value().ground->friction, 0.9);

  // The kinematic pose: down 0.1 m/s for 2 s; from t = 1 also turning about z through the
  // origin, which carries the plate's centre (on the axis) along only vertically.
  const Frame at_half = b[6].poseAt(0.5);
  EXPECT_LT((at_half.origin - Eigen::Vector3d(0, 0, 0.95)).norm(), 1e-12);
  const Frame at_three = b[6].poseAt(3.0);
  EXPECT_LT((at_three.origin - Eigen::Vector3d(0, 0, 0.8)).norm(), 1e-12);
  EXPECT_NEAR(at_three.rotation.angularDistance(Eigen::Quaterniond::Identity()), 2.0, 1e-12);
}

TEST(RigidScene, FaultsNameTheKey) {
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}},
      "mas": 2})")),
                        {"r.json", "rigid_bodies[0].mas", "unknown key"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": "big"}}})")),
                        {"rigid_bodies[0].shape.sphere.radius", "expected a number"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"cone": {}}})")),
                        {"rigid_bodies[0].shape", "needs one of", "capsule", "convex_hull"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}},
      "mass": 1, "kinematic": [{"linear_velocity": [0, 0, 1]}]})")),
                        {"rigid_bodies[0].mass", "kinematic"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}},
      "kinematic": [{"linear_velocty": [0, 0, 1]}]})")),
                        {"rigid_bodies[0].kinematic[0].linear_velocty", "unknown key"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}},
      "kinematic": {"linear_velocity": [0, 0, 1]}})")),
                        {"rigid_bodies[0].kinematic", "expected an array"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"convex_hull": {"points":
      [[0,0,0],[1,0,0],[0,1,0],[1,1,0]]}}})")),
                        {"rigid_bodies[0].shape.convex_hull.points", "flat"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"triangle_mesh": {"vertices":
      [[0,0,0],[1,0,0],[0,1,0]], "triangles": [[0, 1, 3]]}}})")),
                        {"rigid_bodies[0].shape.triangle_mesh.triangles", "vertex 3"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"plane": {"normal": [0,0,1]}},
      "mass": 3})")),
                        {"rigid_bodies[0].mass", "static"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}},
      "mass": 0, "linear_velocity": [1, 0, 0]})")),
                        {"rigid_bodies[0].linear_velocity", "dynamic"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}},
      "friction": -1})")),
                        {"rigid_bodies[0].friction", ">= 0"}));
  EXPECT_TRUE(failsWith(parse(scene(R"({"name": "a", "shape": {"sphere": {"radius": 1}}},
      {"name": "a", "shape": {"sphere": {"radius": 1}}})")),
                        {"rigid_bodies[1].name", "duplicate"}));
  EXPECT_TRUE(failsWith(parse(scene("", R"(, "ground": {"hieght": 0})")),
                        {"ground.hieght", "unknown key"}));
}

// A series names a FEM body's files "<name>_<step>.vtu" and a rigid body's
// "rigid_<name>_<step>.vtu": FEM body "rigid_crate" and rigid body "crate" would overwrite each
// other's, so the scene is refused, naming both. Equal names, or "rigid_" on the rigid side, write
// different files.
TEST(RigidScene, FemAndRigidBodiesWithTheSameSeriesFilesAreRefused) {
  const std::string crate = R"({"name": "crate", "shape": {"sphere": {"radius": 0.1}}})";
  std::string text = scene(crate);
  text.replace(text.find("\"block\""), 7, "\"rigid_crate\"");
  EXPECT_TRUE(failsWith(parse(text), {"r.json: rigid_bodies[0].name", "rigid body 'crate'",
                                      "FEM body 'rigid_crate'", "series/rigid_crate_<step>.vtu"}));
  for (const char* name : {"block", "rigid_block"}) {
    const std::string rigid =
        R"({"name": ")" + std::string(name) + R"(", "shape": {"sphere": {"radius": 0.1}}})";
    Result<SceneSpec> r = parse(scene(rigid));
    EXPECT_TRUE(r.ok()) << name << ": " << r.error().message;
  }
}

// A kinematic plate follows its script exactly (Bullet derives its velocity from the poses the
// scripted motion state hands it), presses the block, and the run writes one rigid.csv row per
// step and the contact figures.
TEST(RigidScene, KinematicPlateFollowsItsScriptAndRunWritesOutputs) {
  Result<SceneSpec> spec = parse(scene(R"(
    {"name": "plate", "shape": {"box": {"half_extents": [0.3, 0.3, 0.05]}},
     "pose": {"position": [0, 0, 0.26]}, "friction": 0.8,
     "kinematic": [{"linear_velocity": [0, 0, -0.1], "duration": 0.3}]})",
                                       R"(, "ground": {"friction": 0.8}, "steps": 40,
     "solver": {"threads": 1})"));
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  auto built = buildScene(std::move(spec).value());
  ASSERT_TRUE(built.ok()) << built.error().message;
  BuiltScene& s = *built.value();
  ASSERT_EQ(s.rigid_bodies.size(), 1u);
  const std::filesystem::path out =
      std::filesystem::temp_directory_path() /
      ("torsion_rigid_scene_test_" + std::to_string(::getpid()));  // one per process
  RunOptions options;
  options.output_directory = out.string();
  Result<RunOutcome> outcome = runScene(s, options);
  ASSERT_TRUE(outcome.ok()) << outcome.error().message;
  ASSERT_TRUE(outcome.value().stable) << outcome.value().failure;
  // Down 3 cm in 0.3 s, then held: at 0.4 s the plate is at 0.23 exactly (scripted, not pushed
  // back by the block it presses 2 cm deep), as exactly as Bullet stores a pose (float Bullet
  // keeps 0.23 as 0.2300000042).
  const btVector3 p = s.rigid_bodies[0].body->getCenterOfMassPosition();
  EXPECT_NEAR(p.z(), 0.23, std::max(1e-12, kBulletEpsilon * 0.23));
  EXPECT_NEAR(p.x(), 0, 1e-12);

  std::ifstream csv(out / "rigid.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("step,time,plate.x,plate.y,plate.z,plate.qx", 0), 0u) << header;
  int rows = 0;
  while (std::getline(csv, line))
    ++rows;
  EXPECT_EQ(rows, 40);
  nlohmann::json summary;
  std::ifstream(out / "summary.json") >> summary;
  ASSERT_TRUE(summary.contains("contacts"));
  EXPECT_GT(summary["contacts"]["active_max"].get<int>(), 16);  // ground and plate
  EXPECT_GT(summary["contacts"]["normal_impulse_total_Ns"].get<double>(), 0);
  EXPECT_LT(summary["contacts"]["max_penetration_m"].get<double>(), 1e-4);
  EXPECT_EQ(summary["contacts"]["unconverged_steps"].get<int>(), 0);
  std::filesystem::remove_all(out);
}

}  // namespace rigid_scene_test
}  // namespace torsion::scene
