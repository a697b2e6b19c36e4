// The body keys "linear_velocity" and "angular_velocity" (docs/scene-format.md, bodies[]): an FEM
// body's rigid motion at the start. Its own file so the main parser test stays as it is.
#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_builder.h"
#include "scene_parser.h"

namespace torsion::scene {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace starting_velocity_key_test {

std::string sceneWith(const std::string& entries) {
  return R"({"gravity": [0, 0, 0], "bodies": [{"name": "cube", "mesh": "cube_384.node",)" +
         entries +
         R"( "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000},
             "pose": {"position": [1, 2, 3]}}]})";
}

Result<SceneSpec> parse(const std::string& entries) {
  return parseScene(sceneWith(entries), "s.json", TORSION_ASSETS_DIR);
}

TEST(SceneStartingVelocityKeys, DefaultToRestAndAreReadAsGiven) {
  Result<SceneSpec> still = parse("");
  ASSERT_TRUE(still.ok()) << still.error().message;
  EXPECT_EQ(still.value().bodies[0].linear_velocity, Eigen::Vector3d::Zero());
  EXPECT_EQ(still.value().bodies[0].angular_velocity, Eigen::Vector3d::Zero());
  Result<SceneSpec> thrown =
      parse(R"( "linear_velocity": [0, 0, -15], "angular_velocity": [0, 2, 0],)");
  ASSERT_TRUE(thrown.ok()) << thrown.error().message;
  EXPECT_EQ(thrown.value().bodies[0].linear_velocity, Eigen::Vector3d(0, 0, -15));
  EXPECT_EQ(thrown.value().bodies[0].angular_velocity, Eigen::Vector3d(0, 2, 0));
}

TEST(SceneStartingVelocityKeys, BadValuesNameTheFileTheKeyAndTheFault) {
  EXPECT_TRUE(test::failsWith(parse(R"( "linear_velocity": [0, 15],)"),
                              {"s.json: bodies[0].linear_velocity", "array of 3 numbers"}));
  EXPECT_TRUE(test::failsWith(parse(R"( "angular_velocity": [0, "1", 0],)"),
                              {"s.json: bodies[0].angular_velocity", "element 1", "number"}));
  EXPECT_TRUE(test::failsWith(
      parse(R"( "linear_velocity": [2e6, 0, 0],)"),
      {"s.json: bodies[0].linear_velocity", "speed 2e+06 m/s", "above the bound 1e+06 m/s"}));
  EXPECT_TRUE(test::failsWith(
      parse(R"( "angular_velocity": [0, 0, -3e7],)"),
      {"s.json: bodies[0].angular_velocity", "spin 3e+07 rad/s", "above the bound 1e+06 rad/s"}));
  EXPECT_TRUE(test::failsWith(parse(R"( "velocity": [1, 0, 0],)"),
                              {"s.json: bodies[0].velocity", "unknown"}));
}

// Built, every node moves as the rigid motion: momentum M v, angular momentum about the centre
// of mass I_c omega (the lumped inertia), each node at v + omega x (x_i - c).
TEST(SceneStartingVelocityKeys, TheBuiltBodyMovesRigidlyAboutItsCentreOfMass) {
  const Eigen::Vector3d v(0.5, -1, 15), omega(0, 2, 1);
  Result<SceneSpec> spec = parse(R"( "linear_velocity": [0.5, -1, 15],
                                     "angular_velocity": [0, 2, 1],)");
  ASSERT_TRUE(spec.ok()) << spec.error().message;
  auto built = buildScene(std::move(spec).value(), BuildOptions{1});
  ASSERT_TRUE(built) << built.error().message;
  const FemBody& body = *built.value()->world->bodies().front();
  const std::vector<double>& m = body.model().nodeMasses();
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), p = Eigen::Vector3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    c += m[static_cast<size_t>(i)] * body.state().position(i);
    p += m[static_cast<size_t>(i)] * body.state().velocity(i);
  }
  c /= body.model().totalMass();
  EXPECT_NEAR((c - Eigen::Vector3d(1, 2, 3)).norm(), 0, 1e-12) << "the cube centred on its pose";
  EXPECT_NEAR((p - body.model().totalMass() * v).norm(), 0, 1e-9 * p.norm());
  Eigen::Vector3d l = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia = Eigen::Matrix3d::Zero();
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    const Eigen::Vector3d r = body.state().position(i) - c;
    l += m[static_cast<size_t>(i)] * r.cross(body.state().velocity(i));
    inertia += m[static_cast<size_t>(i)] *
               (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
    EXPECT_NEAR((body.state().velocity(i) - (v + omega.cross(r))).norm(), 0, 1e-12) << i;
  }
  EXPECT_NEAR((l - inertia * omega).norm(), 0, 1e-9 * l.norm());
}

}  // namespace starting_velocity_key_test
}  // namespace torsion::scene
