// Scene files: a complete valid scene, and one test per kind of bad input, each checking that the
// error names the file and the key path (or line:column for JSON syntax).
#include "scene_parser.h"

#include <gtest/gtest.h>

#include "../unit/error_matchers.h"

namespace torsion::scene {
namespace {

using test::failsWith;

const std::string kValid = R"({
  "name": "twist",
  "gravity": [0, 0, 0],
  "steps": 50,
  "solver": {"dt": 0.005, "linear_solver": "cholmod", "tolerance": 1e-6, "threads": 1},
  "bodies": [{"name": "cyl", "mesh": "meshes/cyl.node",
              "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000},
              "pose": {"position": [1, 0, 0], "axis_angle": {"axis": [0, 0, 1], "angle": 0.5}}}],
  "node_sets": [
    {"name": "base", "body": "cyl", "select": {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1]}}},
    {"name": "end", "body": "cyl", "select": {"box": {"min": [-2, -2, 9.9], "max": [2, 2, 10.1]}},
     "motion": {"angular_velocity": [0, 0, 0.1], "pivot": [0, 0, 10], "duration": 5},
     "wrench_about": [0, 0, 10]}
  ],
  "rigid_bodies": [{"name": "ground", "shape": {"plane": {"normal": [0, 0, 1], "offset": -1}}},
                   {"name": "ball", "shape": {"sphere": {"radius": 0.2}}, "mass": 2,
                    "pose": {"position": [0, 0, 12]}}]
})";

Result<SceneSpec> parse(const std::string& text) {
  return parseScene(text, "s.json", "/base");
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(SceneParser, ReadsACompleteScene) {
  Result<SceneSpec> r = parse(kValid);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const SceneSpec& s = r.value();
  EXPECT_EQ(s.name, "twist");
  EXPECT_EQ(s.steps, 50);
  EXPECT_EQ(s.world.solver.linear_solver, LinearSolverKind::kCholmod);
  EXPECT_DOUBLE_EQ(s.world.solver.time_step, 0.005);
  ASSERT_EQ(s.bodies.size(), 1u);
  EXPECT_EQ(s.bodies[0].mesh_path, "/base/meshes/cyl.node");
  EXPECT_NEAR(s.bodies[0].pose.rotation.angularDistance(
                  Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()))),
              0, 1e-12);
  ASSERT_EQ(s.node_sets.size(), 2u);
  EXPECT_TRUE(s.node_sets[0].fixed);
  EXPECT_FALSE(s.node_sets[1].fixed);
  EXPECT_EQ(s.rigid_bodies.size(), 2u);
  EXPECT_EQ(s.rigid_bodies[0].mass, 0.0);
}

TEST(SceneParser, MotionRotatesAboutPivotThenHolds) {
  MotionSpec m;
  m.angular_velocity = Eigen::Vector3d(0, 0, 0.5);
  m.pivot = Eigen::Vector3d(1, 0, 0);
  m.duration = 2;
  const Eigen::Vector3d p(2, 0, 0);
  EXPECT_LT((m.frameAt(0).toWorld(p) - p).norm(), 1e-15);
  const Eigen::Vector3d quarter(1, 1,
                                0);  // 0.5 rad/s for pi s would be a quarter turn; hold at 1 rad
  EXPECT_LT(
      (m.frameAt(M_PI).toWorld(p) - Eigen::Vector3d(1 + std::cos(1.0), std::sin(1.0), 0)).norm(),
      1e-12);
  (void)quarter;
}

TEST(SceneParserFaults, JsonSyntaxNamesLineAndColumn) {
  EXPECT_TRUE(
      failsWith(parse("{\n  \"steps\": 10,\n  \"bodies\": [\n}"), {"s.json:4:", "invalid JSON"}));
}

TEST(SceneParserFaults, UnknownKeyIsNamedWithItsPath) {
  // A misspelt optional key is an unknown key; a misspelt required one is named as both.
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"linear_solver\"", "\"linearsolver\"")),
                        {"s.json: solver.linearsolver: unknown key", "linear_solver"}));
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"density\"", "\"densty\"")),
                        {"s.json: bodies[0].material.density: missing (required); did you mean "
                         "'densty'?"}));
}

TEST(SceneParserFaults, AMissingKeyDoesNotCallValidKeysNotYetReadUnknown) {
  // "name" is read first: "mesh", "material" and "pose" are valid keys read after it.
  const Result<SceneSpec> spec = parse(replaced(kValid, "\"name\": \"cyl\", ", ""));
  ASSERT_FALSE(spec.ok());
  EXPECT_EQ(spec.error().message, "s.json: bodies[0].name: missing (required)");
}

TEST(SceneParserFaults, BadValuesAreShownInShortestForm) {
  // std::to_string showed -1e-9 as "-0.000000", hiding the value that was wrong.
  EXPECT_TRUE(
      failsWith(parse(replaced(kValid, "\"youngs_modulus\": 1e5", "\"youngs_modulus\": -1e-9")),
                {"youngs_modulus = -1e-09: must be > 0 Pa"}));
}

TEST(SceneParserFaults, DuplicateKeysAndHugeNumbersAreNamed) {
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"steps\": 50", "\"steps\": 50, \"steps\": 5")),
                        {"s.json: invalid JSON: duplicate key 'steps' in the top-level object"}));
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"steps\": 50", "\"steps\": 5e999")),
                        {"s.json:4:12: invalid JSON: number out of range of a double: 5e999"}));
}

TEST(SceneParserFaults, WrongTypeIsNamed) {
  std::string text = kValid;
  text.replace(text.find("\"steps\": 50"), 11, "\"steps\": \"50\"");
  EXPECT_TRUE(failsWith(parse(text), {"s.json: steps: expected an integer, found a string"}));
  text = kValid;
  text.replace(text.find("[1, 0, 0]"), 9, "[1, 0]");
  EXPECT_TRUE(failsWith(parse(text), {"bodies[0].pose.position: expected an array of 3 numbers"}));
}

TEST(SceneParserFaults, MissingRequiredKey) {
  std::string text = kValid;
  text.replace(text.find("\"poisson_ratio\": 0.3, "), 22, "");
  EXPECT_TRUE(failsWith(parse(text), {"bodies[0].material.poisson_ratio: missing (required)"}));
}

TEST(SceneParserFaults, OutOfRangeValues) {
  std::string text = kValid;
  text.replace(text.find("\"poisson_ratio\": 0.3"), 20, "\"poisson_ratio\": 0.5");
  EXPECT_TRUE(failsWith(parse(text), {"bodies[0].material", "poisson_ratio", "[0, 0.5)"}));
  text = kValid;
  text.replace(text.find("\"dt\": 0.005"), 11, "\"dt\": -1");
  EXPECT_TRUE(failsWith(parse(text), {"s.json: solver", "time_step"}));
}

TEST(SceneParser, SelfContactIsOnWhereAskedForWithItsSettings) {
  Result<SceneSpec> off = parse(kValid);
  ASSERT_TRUE(off.ok()) << off.error().message;
  EXPECT_FALSE(off.value().bodies[0].self_contact.has_value());
  Result<SceneSpec> on = parse(replaced(kValid, R"("mesh": "meshes/cyl.node",)",
                                        R"("mesh": "meshes/cyl.node",
                                           "self_contact": {"friction": 0.5},)"));
  ASSERT_TRUE(on.ok()) << on.error().message;
  ASSERT_TRUE(on.value().bodies[0].self_contact.has_value());
  EXPECT_EQ(on.value().bodies[0].self_contact->friction, 0.5);
  EXPECT_EQ(on.value().bodies[0].self_contact->gap_tolerance, 0.0);  // from the mesh
}

TEST(SceneParser, FemContactIsOnByDefaultSetByItsKeyAndOffWhenDisabled) {
  Result<SceneSpec> plain = parse(kValid);
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  ASSERT_TRUE(plain.value().fem_contact.has_value());
  EXPECT_EQ(plain.value().fem_contact->friction, BodyContactSettings{}.friction);
  Result<SceneSpec> set = parse(
      replaced(kValid, R"("steps": 50,)", R"("steps": 50, "fem_contact": {"friction": 0.6},)"));
  ASSERT_TRUE(set.ok()) << set.error().message;
  ASSERT_TRUE(set.value().fem_contact.has_value());
  EXPECT_EQ(set.value().fem_contact->friction, 0.6);
  Result<SceneSpec> off = parse(
      replaced(kValid, R"("steps": 50,)", R"("steps": 50, "fem_contact": {"enabled": false},)"));
  ASSERT_TRUE(off.ok()) << off.error().message;
  EXPECT_FALSE(off.value().fem_contact.has_value());
}

TEST(SceneParserFaults, BadFemContactSettingsAreNamed) {
  EXPECT_TRUE(failsWith(parse(replaced(kValid, R"("steps": 50,)",
                                       R"("steps": 50, "fem_contact": {"friction": -1},)")),
                        {"fem_contact", "friction", ">= 0"}));
  EXPECT_TRUE(failsWith(
      parse(replaced(kValid, R"("steps": 50,)", R"("steps": 50, "fem_contact": {"mu": 1},)")),
      {"fem_contact", "mu"}));
}

TEST(SceneParserFaults, BadSelfContactSettingsAreNamed) {
  EXPECT_TRUE(failsWith(parse(replaced(kValid, R"("mesh": "meshes/cyl.node",)",
                                       R"("mesh": "meshes/cyl.node",
                                          "self_contact": {"friction": -1},)")),
                        {"bodies[0]", "self_contact", "friction", ">= 0"}));
  EXPECT_TRUE(failsWith(parse(replaced(kValid, R"("mesh": "meshes/cyl.node",)",
                                       R"("mesh": "meshes/cyl.node",
                                          "self_contact": {"penalty": 3},)")),
                        {"bodies[0].self_contact", "penalty"}));
}

TEST(SceneParserFaults, UnknownBodyInNodeSet) {
  std::string text = kValid;
  text.replace(text.find("\"body\": \"cyl\""), 13, "\"body\": \"cyl2\"");
  EXPECT_TRUE(failsWith(parse(text), {"node_sets[0].body: no body named 'cyl2'"}));
}

TEST(SceneParserFaults, SelectionNeedsExactlyOneShape) {
  const std::string text =
      replaced(kValid, "{\"plane\": {\"point\": [0, 0, 0], \"normal\": [0, 0, 1]}}", "{}");
  EXPECT_TRUE(failsWith(parse(text), {"node_sets[0].select: needs one of: plane, box, sphere"}));
}

TEST(SceneParserFaults, UnknownSolverName) {
  std::string text = kValid;
  text.replace(text.find("\"cholmod\""), 9, "\"lu\"");
  EXPECT_TRUE(failsWith(parse(text), {"solver.linear_solver: 'lu' is not one of: cg, cholmod"}));
}

TEST(SceneParser, ReadsALaggedPreconditionerAndItsRefactorisationPolicy) {
  const std::string text = replaced(kValid, "\"tolerance\": 1e-6,",
                                    "\"tolerance\": 1e-6, \"preconditioner\": \"two_level\", "
                                    "\"refactor_interval\": 20, \"refactor_iterations\": 5,");
  Result<SceneSpec> r = parse(text);
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r.value().world.solver.preconditioner, PreconditionerKind::kTwoLevel);
  EXPECT_EQ(r.value().world.solver.refactor_interval, 20);
  EXPECT_EQ(r.value().world.solver.refactor_iterations, 5);
}

TEST(SceneParser, ReadsTheNewtonSolveOfHyperelasticBodies) {
  Result<SceneSpec> defaults = parse(kValid);
  ASSERT_TRUE(defaults.ok()) << defaults.error().message;
  EXPECT_EQ(defaults.value().world.solver.newton_tolerance, SolverSettings{}.newton_tolerance);
  EXPECT_EQ(defaults.value().world.solver.newton_max_iterations,
            SolverSettings{}.newton_max_iterations);
  Result<SceneSpec> r = parse(replaced(kValid, "\"tolerance\": 1e-6,",
                                       "\"tolerance\": 1e-6, \"newton_tolerance\": 1e-8, "
                                       "\"newton_max_iterations\": 12,"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  EXPECT_EQ(r.value().world.solver.newton_tolerance, 1e-8);
  EXPECT_EQ(r.value().world.solver.newton_max_iterations, 12);
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"tolerance\": 1e-6,",
                                       "\"tolerance\": 1e-6, \"newton_tolerance\": 0,")),
                        {"s.json: solver", "newton_tolerance = 0"}));
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"tolerance\": 1e-6,",
                                       "\"tolerance\": 1e-6, \"newton_max_iterations\": 0,")),
                        {"s.json: solver", "newton_max_iterations = 0"}));
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"tolerance\": 1e-6,",
                                       "\"tolerance\": 1e-6, \"newton_max_iterations\": 2.5,")),
                        {"solver.newton_max_iterations"}));
}

TEST(SceneParserFaults, UnknownPreconditionerAndZeroRefactorInterval) {
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"tolerance\": 1e-6,",
                                       "\"tolerance\": 1e-6, \"preconditioner\": \"ilu\",")),
                        {"solver.preconditioner: 'ilu' is not one of: jacobi, block_jacobi, "
                         "lagged_cholesky, incomplete_cholesky, two_level"}));
  EXPECT_TRUE(failsWith(parse(replaced(kValid, "\"tolerance\": 1e-6,",
                                       "\"tolerance\": 1e-6, \"refactor_interval\": 0,")),
                        {"refactor_interval = 0: must be >= 1"}));
}

TEST(SceneParserFaults, NonFiniteNumbersAndZeroAxis) {
  std::string text = kValid;
  text.replace(text.find("\"axis\": [0, 0, 1]"), 17, "\"axis\": [0, 0, 0]");
  EXPECT_TRUE(failsWith(parse(text), {"bodies[0].pose.axis_angle.axis: must not be zero"}));
}

TEST(SceneParserFaults, NoBodies) {
  EXPECT_TRUE(
      failsWith(parse("{\"steps\": 3}"), {"s.json: bodies: a scene needs at least one FEM body"}));
}

TEST(SceneParserFaults, TopLevelMustBeAnObject) {
  EXPECT_TRUE(
      failsWith(parse("[1, 2]"), {"s.json: the scene: expected an object, found an array"}));
}

}  // namespace
}  // namespace torsion::scene

namespace torsion::scene {
namespace {

const std::string kWithHand = R"({
  "bodies": [{"name": "cyl", "mesh": "c.node",
              "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}],
  "hands": [{"name": "right", "body": "cyl",
             "frame": {"origin": [0, 0, 9.9], "i": [1, 0, 0], "j": [0, 1, 0]},
             "motion": {"angular_velocity": [0, 0, 0.5], "pivot": [0, 0, 9.9], "duration": 2},
             "grab_at": 0.5, "release_at": 3}]
})";

Result<SceneSpec> parseHand(const std::string& text) {
  return parseScene(text, "h.json", "/");
}

std::string with(const std::string& from, const std::string& to) {
  std::string text = kWithHand;
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(SceneHands, ReadsAHandAndFollowsItsMotion) {
  Result<SceneSpec> r = parseHand(kWithHand);
  ASSERT_TRUE(r.ok()) << r.error().message;
  ASSERT_EQ(r.value().hands.size(), 1u);
  const HandSpec& h = r.value().hands[0];
  EXPECT_EQ(h.grab_at, 0.5);
  EXPECT_EQ(h.release_at, 3.0);
  // After 1 s at 0.5 rad/s about z through the origin's axis: O fixed, i turned by 0.5 rad.
  const Frame f = h.frameAt(1.0);
  EXPECT_LT((f.origin - Eigen::Vector3d(0, 0, 9.9)).norm(), 1e-12);
  EXPECT_LT(
      (f.rotation * Eigen::Vector3d::UnitX() - Eigen::Vector3d(std::cos(0.5), std::sin(0.5), 0))
          .norm(),
      1e-12);
  EXPECT_LT((h.frameAt(10).rotation * Eigen::Vector3d::UnitX() -
             Eigen::Vector3d(std::cos(1.0), std::sin(1.0), 0))
                .norm(),
            1e-12);
}

TEST(SceneHands, KeyframesInterpolateOriginLinearlyAndRotationBySlerp) {
  const std::string keyed =
      with(R"("frame": {"origin": [0, 0, 9.9], "i": [1, 0, 0], "j": [0, 1, 0]},
             "motion": {"angular_velocity": [0, 0, 0.5], "pivot": [0, 0, 9.9], "duration": 2},)",
           R"("keyframes": [{"time": 0, "origin": [0, 0, 0]},
                           {"time": 2, "origin": [2, 0, 0], "axis_angle": {"axis": [0, 0, 1], "angle": 1.0}}],)");
  Result<SceneSpec> r = parseHand(keyed);
  ASSERT_TRUE(r.ok()) << r.error().message;
  const Frame mid = r.value().hands[0].frameAt(1.0);
  EXPECT_LT((mid.origin - Eigen::Vector3d(1, 0, 0)).norm(), 1e-12);
  EXPECT_NEAR(mid.rotation.angularDistance(Eigen::Quaterniond::Identity()), 0.5, 1e-12);
  EXPECT_LT((r.value().hands[0].frameAt(5.0).origin - Eigen::Vector3d(2, 0, 0)).norm(),
            1e-12);  // held
}

TEST(SceneHandsFaults, UnknownBody) {
  EXPECT_TRUE(test::failsWith(parseHand(with(R"("body": "cyl",
             "frame")",
                                             R"("body": "arm",
             "frame")")),
                              {"h.json: hands[0].body: no body named 'arm'"}));
}

TEST(SceneHandsFaults, DegenerateRotation) {
  EXPECT_TRUE(test::failsWith(parseHand(with(R"("j": [0, 1, 0])", R"("j": [0.5, 1, 0])")),
                              {"h.json: hands[0].frame.i: degenerate rotation", "orthonormal"}));
}

TEST(SceneHandsFaults, KeyframesOutOfOrder) {
  const std::string keyed = with(
      R"("frame": {"origin": [0, 0, 9.9], "i": [1, 0, 0], "j": [0, 1, 0]},
             "motion": {"angular_velocity": [0, 0, 0.5], "pivot": [0, 0, 9.9], "duration": 2},)",
      R"("keyframes": [{"time": 1, "origin": [0, 0, 0]}, {"time": 0.5, "origin": [1, 0, 0]}],)");
  EXPECT_TRUE(
      test::failsWith(parseHand(keyed), {"h.json: hands[0].keyframes[1].time", "time order"}));
}

TEST(SceneHandsFaults, ReleaseBeforeGrabAndNonNumbers) {
  EXPECT_TRUE(test::failsWith(parseHand(with(R"("release_at": 3)", R"("release_at": 0.2)")),
                              {"hands[0].release_at: must be after grab_at"}));
  EXPECT_TRUE(
      test::failsWith(parseHand(with(R"("origin": [0, 0, 9.9])", R"("origin": [0, "x", 9.9])")),
                      {"hands[0].frame.origin: element 1: expected a number"}));
}

TEST(SceneHands, SpeedLimitDefaultsAndIsRead) {
  Result<SceneSpec> plain = parseHand(kWithHand);
  ASSERT_TRUE(plain.ok()) << plain.error().message;
  EXPECT_EQ(plain.value().hands[0].settings.max_drag_strain, HandSettings{}.max_drag_strain);
  Result<SceneSpec> off =
      parseHand(with(R"("release_at": 3)", R"("release_at": 3, "max_drag_strain": 0)"));
  ASSERT_TRUE(off.ok()) << off.error().message;
  EXPECT_EQ(off.value().hands[0].settings.max_drag_strain, 0.0);
  EXPECT_TRUE(test::failsWith(
      parseHand(with(R"("release_at": 3)", R"("release_at": 3, "max_drag_strain": -1)")),
      {"h.json: hands[0].max_drag_strain: must be >= 0"}));
}

}  // namespace
}  // namespace torsion::scene
