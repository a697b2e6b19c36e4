// The `device` entry of a scene hand and the CLI's --device / --haptics: a complete device of
// each kind, and one case per kind of bad input, each checking the error names the key.
#include "device_parser.h"

#include <gtest/gtest.h>

#include "../unit/error_matchers.h"
#include "scene_builder.h"
#include "scene_parser.h"

namespace torsion::scene {
// Named, not anonymous: its helpers share a unity batch with other files' (TORSION_UNITY_BUILD).
namespace device_parser_test {

using test::failsWith;

// A scene whose one hand carries `device` (a JSON object text) or `extra` hand keys.
std::string sceneWith(const std::string& device, const std::string& extra = "") {
  return R"({"bodies": [{"name": "cyl", "mesh": "cyl.node",
              "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}],
  "hands": [{"name": "hand", "body": "cyl",
             "frame": {"origin": [0, 0, 9.9], "i": [1, 0, 0], "j": [0, 1, 0]})" +
         (device.empty() ? "" : ", \"device\": " + device) + extra + "}]}";
}

Result<SceneSpec> parse(const std::string& text) {
  return parseScene(text, "s.json", "/base");
}

TEST(DeviceParser, ReadsAScriptedDeviceWithEverySetting) {
  Result<SceneSpec> r = parse(sceneWith(R"({"type": "scripted", "trajectory": "t/fig.json",
      "speed": 10, "mapping": {"position_scale": 10, "force_scale": 0.1, "torque_scale": 0.01},
      "rendering": "frame_difference",
      "coupling": {"force_coefficient": 0.2, "torque_coefficient": 0.04, "stiffness_refresh_steps": 5},
      "limits": {"max_force": 12, "max_torque": 1.5}, "rate_hz": 500, "step_blend_hz": 5,
      "damper": {"linear": 2, "angular": 0.1},
      "passivity": {"enabled": true, "length_scale": 0.05, "rate_limited": true,
                    "speed_hold_time": 0.2, "speed_margin": 3, "energy_tolerance": 1e-5,
                    "misprediction_margin": 0},
      "safety": {"max_force_rate": 100, "max_torque_rate": 10, "stale_after": 0.05, "fade_time": 0.3}})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const HandSpec& h = r.value().hands.at(0);
  ASSERT_TRUE(h.device.has_value());
  const DeviceSpec& d = *h.device;
  EXPECT_EQ(d.kind, DeviceSpec::Kind::kScripted);
  EXPECT_EQ(d.file, "/base/t/fig.json");  // relative to the scene file
  EXPECT_EQ(d.speed, 10);
  EXPECT_EQ(d.position_scale, 10);
  EXPECT_EQ(d.force_scale, 0.1);
  EXPECT_EQ(d.torque_scale, 0.01);
  EXPECT_EQ(d.coupling.rendering, haptics::Rendering::kFrameDifference);
  EXPECT_EQ(d.coupling.force_coefficient, 0.2);
  EXPECT_EQ(d.coupling.stiffness_refresh_steps, 5);
  EXPECT_EQ(d.max_force, 12);
  EXPECT_EQ(d.max_torque, 1.5);
  EXPECT_EQ(d.loop.rate_hz, 500);
  EXPECT_EQ(d.loop.step_blend_hz, 5);
  EXPECT_EQ(d.loop.damper.linear, 2);
  EXPECT_EQ(d.loop.passivity.length_scale, 0.05);
  EXPECT_TRUE(d.loop.passivity.rate_limited);
  EXPECT_EQ(d.loop.passivity.speed_hold_time, 0.2);
  EXPECT_EQ(d.loop.passivity.speed_margin, 3);
  EXPECT_EQ(d.loop.passivity.energy_tolerance, 1e-5);
  EXPECT_EQ(d.loop.passivity.misprediction_margin, 0);
  EXPECT_EQ(d.loop.safety.fade_time, 0.3);
  EXPECT_EQ(h.initial.origin.z(), 9.9);  // the device's anchor
}

TEST(DeviceParser, ReadsNetworkReplayAndSpaceMouse) {
  Result<SceneSpec> net =
      parse(sceneWith(R"({"type": "network", "host": "127.0.0.1", "port": 6001, "timeout": 0.1})"));
  ASSERT_TRUE(net.ok()) << net.error().message;
  EXPECT_EQ(net.value().hands[0].device->kind, DeviceSpec::Kind::kNetwork);
  EXPECT_EQ(net.value().hands[0].device->port, 6001);
  Result<SceneSpec> replay = parse(sceneWith(R"({"type": "replay", "log": "/abs/run.csv"})"));
  ASSERT_TRUE(replay.ok()) << replay.error().message;
  EXPECT_EQ(replay.value().hands[0].device->file, "/abs/run.csv");
  Result<SceneSpec> mouse =
      parse(sceneWith(R"({"type": "spacemouse", "max_linear_speed": 0.05, "dead_zone": 20})"));
  ASSERT_TRUE(mouse.ok()) << mouse.error().message;
  EXPECT_EQ(mouse.value().hands[0].device->spacemouse.dead_zone, 20);
}

TEST(DeviceParser, APluginRunsIsolatedUnlessTheSceneSaysOtherwise) {
  Result<SceneSpec> isolated = parse(sceneWith(R"({"type": "plugin", "library": "/a/libd.so"})"));
  ASSERT_TRUE(isolated.ok()) << isolated.error().message;
  EXPECT_TRUE(isolated.value().hands[0].device->isolated);
  Result<SceneSpec> inproc =
      parse(sceneWith(R"({"type": "plugin", "library": "/a/libd.so", "isolated": false})"));
  ASSERT_TRUE(inproc.ok()) << inproc.error().message;
  EXPECT_FALSE(inproc.value().hands[0].device->isolated);
  EXPECT_TRUE(
      failsWith(parse(sceneWith(R"({"type": "plugin", "library": "/a/libd.so", "isolated": 1})")),
                {"s.json: hands[0].device.isolated: expected true or false"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "replay", "log": "a", "isolated": true})")),
                        {"hands[0].device.isolated: unknown key"}));  // plug-ins only
}

TEST(DeviceParser, BadInputNamesTheKey) {
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "joystick"})")),
                        {"s.json: hands[0].device.type: 'joystick' is not one of"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "scripted"})")),
                        {"hands[0].device.trajectory: missing (required)"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "scripted", "trajectory": 3})")),
                        {"hands[0].device.trajectory: expected a string, found a number"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "scripted", "trajectory": "a", "sped": 2})")),
                        {"hands[0].device.sped: unknown key"}));
  // Keys of another device type are unknown here, not silently ignored.
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "scripted", "trajectory": "a", "port": 1})")),
                        {"hands[0].device.port: unknown key"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "network", "port": 70000})")),
                        {"hands[0].device.port: must be in [0, 65535]"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "network", "host": "localhost"})")),
                        {"hands[0].device.host: 'localhost' is not an IPv4 address"}));
  EXPECT_TRUE(failsWith(
      parse(sceneWith(R"({"type": "replay", "log": "a", "mapping": {"position_scale": 0}})")),
      {"hands[0].device.mapping.position_scale: must be > 0"}));
  EXPECT_TRUE(
      failsWith(parse(sceneWith(R"({"type": "replay", "log": "a", "rendering": "spring"})")),
                {"hands[0].device.rendering: 'spring' is not one of"}));
  EXPECT_TRUE(
      failsWith(parse(sceneWith(R"({"type": "replay", "log": "a", "limits": {"max_force": -1}})")),
                {"hands[0].device.limits.max_force: must be >= 0"}));
  EXPECT_TRUE(failsWith(
      parse(
          sceneWith(R"({"type": "replay", "log": "a", "passivity": {"energy_tolerance": -1e-5}})")),
      {"hands[0].device.passivity.energy_tolerance: must be >= 0 J"}));
  EXPECT_TRUE(failsWith(
      parse(sceneWith(R"({"type": "replay", "log": "a", "passivity": {"rate_limited": 1}})")),
      {"hands[0].device.passivity.rate_limited: expected"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "spacemouse", "limits": {"max_force": 1}})")),
                        {"hands[0].device.limits: unknown key"}));  // no motors, no force limits
  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "replay", "log": "a", "speed": 0})")),
                        {"hands[0].device.speed: must be > 0"}));
  EXPECT_TRUE(failsWith(parse(sceneWith(R"("scripted")")),
                        {"hands[0].device: expected an object, found a string"}));
}

TEST(DeviceParser, ADeviceHandHasNoScript) {
  for (const char* key :
       {"\"motion\": {\"angular_velocity\": [0, 0, 1]}", "\"grab_at\": 1", "\"release_at\": 2"}) {
    EXPECT_TRUE(
        failsWith(parse(sceneWith(R"({"type": "replay", "log": "a"})", std::string(", ") + key)),
                  {"s.json: hands[0].", "a hand with a device is moved by the device"}))
        << key;
  }
}

TEST(DeviceOverride, TurnsAScriptedHandIntoADeviceHand) {
  Result<SceneSpec> r = parse(
      sceneWith("", R"(, "motion": {"angular_velocity": [0, 0, 0.1], "pivot": [0, 0, 9.9]})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  SceneSpec s = r.value();
  ASSERT_TRUE(applyDeviceOverride(s, "hand=network:10.0.0.2:6100").ok());
  ASSERT_TRUE(s.hands[0].device.has_value());
  EXPECT_EQ(s.hands[0].device->kind, DeviceSpec::Kind::kNetwork);
  EXPECT_EQ(s.hands[0].device->host, "10.0.0.2");
  EXPECT_EQ(s.hands[0].device->port, 6100);
  EXPECT_EQ(s.hands[0].motion.angular_velocity.norm(), 0);  // the script gives way
  EXPECT_EQ(s.hands[0].initial.origin.z(), 9.9);            // its start is the anchor

  ASSERT_TRUE(applyDeviceOverride(s, "hand=network:6200").ok());
  EXPECT_EQ(s.hands[0].device->port, 6200);
  ASSERT_TRUE(applyDeviceOverride(s, "hand=replay:log.csv").ok());
  EXPECT_EQ(s.hands[0].device->kind, DeviceSpec::Kind::kReplay);
  EXPECT_EQ(s.hands[0].device->file, "log.csv");
  // plugin:LIBRARY[:CONFIG]: the configuration is everything after the library, colons included.
  ASSERT_TRUE(applyDeviceOverride(s, "hand=plugin:/opt/libdev.so:port=/dev/ttyUSB0,gain=2:x").ok());
  EXPECT_EQ(s.hands[0].device->kind, DeviceSpec::Kind::kPlugin);
  EXPECT_EQ(s.hands[0].device->file, "/opt/libdev.so");
  EXPECT_EQ(s.hands[0].device->config, "port=/dev/ttyUSB0,gain=2:x");
  ASSERT_TRUE(applyDeviceOverride(s, "hand=plugin:libdev.so").ok());
  EXPECT_EQ(s.hands[0].device->config, "");
  EXPECT_TRUE(s.hands[0].device->isolated);
  // plugin-inproc: the same, in Torsion's process.
  ASSERT_TRUE(applyDeviceOverride(s, "hand=plugin-inproc:/opt/libdev.so:gain=2").ok());
  EXPECT_EQ(s.hands[0].device->kind, DeviceSpec::Kind::kPlugin);
  EXPECT_EQ(s.hands[0].device->file, "/opt/libdev.so");
  EXPECT_EQ(s.hands[0].device->config, "gain=2");
  EXPECT_FALSE(s.hands[0].device->isolated);
}

TEST(DeviceOverride, KeepsTheScenesMappingAndNamesFaults) {
  Result<SceneSpec> r = parse(sceneWith(
      R"({"type": "scripted", "trajectory": "a.json", "mapping": {"position_scale": 10}})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  SceneSpec s = r.value();
  ASSERT_TRUE(applyDeviceOverride(s, "hand=spacemouse").ok());
  EXPECT_EQ(s.hands[0].device->kind, DeviceSpec::Kind::kSpaceMouse);
  EXPECT_EQ(s.hands[0].device->position_scale, 10);

  EXPECT_TRUE(failsWith(
      applyDeviceOverride(s, "foot=network:1"),
      {"--device 'foot=network:1'", "no hand or dynamic rigid body named 'foot'", "'hand'"}));
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "network:1"), {"expected NAME=TYPE[:ARG]"}));
  EXPECT_TRUE(
      failsWith(applyDeviceOverride(s, "hand=network:port"), {"port 'port' is not a number"}));
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "hand=scripted"), {"scripted needs a file"}));
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "hand=glove"), {"unknown device type 'glove'"}));
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "hand=plugin"), {"plugin needs a shared library"}));
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "hand=plugin-inproc"),
                        {"plugin-inproc needs a shared library: plugin-inproc:LIBRARY[:CONFIG]"}));
  EXPECT_TRUE(failsWith(parseHapticsMode("fast"), {"--haptics 'fast'", "lockstep or threaded"}));
  EXPECT_TRUE(parseHapticsMode("threaded").ok());
}

// A scene with one rigid body `body` (JSON object text) beside the hand of sceneWith("").
std::string sceneWithRigidBody(const std::string& body) {
  std::string scene = sceneWith("");
  scene.pop_back();  // the closing brace
  return scene + R"(, "rigid_bodies": [)" + body + "]}";
}

TEST(ToolDevice, ADynamicRigidBodyWithADeviceIsATool) {
  Result<SceneSpec> r = parse(sceneWithRigidBody(R"({"name": "probe", "mass": 0.02,
      "shape": {"sphere": {"radius": 0.01}},
      "device": {"type": "scripted", "trajectory": "t/p.json", "limits": {"max_force": 8},
                 "coupling": {"stiffness": 700, "angular_stiffness": 2, "damping_ratio": 0.5,
                              "max_force": 40, "max_torque": 4, "feel_weight": true},
                 "rate_hz": 500}})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const RigidBodySpec& probe = r.value().rigid_bodies.at(0);
  ASSERT_TRUE(probe.isTool());
  const DeviceSpec& d = *probe.device;
  EXPECT_EQ(d.file, "/base/t/p.json");
  EXPECT_EQ(d.max_force, 8);
  EXPECT_EQ(d.tool.stiffness, 700);
  EXPECT_EQ(d.tool.angular_stiffness, 2);
  EXPECT_EQ(d.tool.damping_ratio, 0.5);
  EXPECT_EQ(d.tool.max_force, 40);
  EXPECT_EQ(d.tool.max_torque, 4);
  EXPECT_TRUE(d.tool.feel_weight);
  EXPECT_EQ(d.loop.rate_hz, 500);
  EXPECT_FALSE(d.loop.buttons_switch_force) << "a tool is held from the start";
}

TEST(ToolDevice, FaultsNameTheRigidBodyAndTheKey) {
  const std::string sphere = R"("shape": {"sphere": {"radius": 0.01}})";
  const std::string device = R"("device": {"type": "scripted", "trajectory": "p.json")";
  EXPECT_TRUE(failsWith(
      parse(sceneWithRigidBody(R"({"name": "wall", "mass": 0, )" + sphere + ", " + device + "}}")),
      {"s.json", "rigid_bodies[0]", "device", "must be a dynamic body (mass > 0)"}));
  EXPECT_TRUE(failsWith(parse(sceneWithRigidBody(R"({"name": "p", "mass": 1, )" + sphere + ", " +
                                                 device + R"(, "rendering": "internal_force"}})")),
                        {"rigid_bodies[0]", "rendering", "a hand's key"}));
  EXPECT_TRUE(failsWith(parse(sceneWithRigidBody(R"({"name": "p", "mass": 1, )" + sphere + ", " +
                                                 device + R"(, "coupling": {"stiffness": 0}}})")),
                        {"rigid_bodies[0]", "coupling", "stiffness", "must be > 0"}));
  EXPECT_TRUE(
      failsWith(parse(sceneWithRigidBody(R"({"name": "p", "mass": 1, )" + sphere + ", " + device +
                                         R"(, "coupling": {"force_coefficient": 0.1}}})")),
                {"rigid_bodies[0]", "coupling", "force_coefficient"}));
}

TEST(ToolDevice, TheCommandLineHandsADynamicRigidBodyADevice) {
  Result<SceneSpec> r = parse(sceneWithRigidBody(
      R"({"name": "probe", "mass": 0.02, "shape": {"sphere": {"radius": 0.01}}},
         {"name": "wall", "mass": 0, "shape": {"box": {"half_extents": [1, 1, 1]}}})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  SceneSpec s = r.value();
  ASSERT_TRUE(applyDeviceOverride(s, "probe=network:5751").ok());
  ASSERT_TRUE(s.rigid_bodies[0].isTool());
  EXPECT_EQ(s.rigid_bodies[0].device->kind, DeviceSpec::Kind::kNetwork);
  EXPECT_EQ(s.rigid_bodies[0].device->port, 5751);
  EXPECT_FALSE(s.rigid_bodies[0].device->loop.buttons_switch_force);
  EXPECT_FALSE(s.hands[0].device.has_value());
  // A static body cannot be a tool; the message lists what can.
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "wall=spacemouse"),
                        {"no hand or dynamic rigid body named 'wall'", "hands: 'hand'",
                         "dynamic rigid bodies: 'probe'"}));
}

// `manual`: a tool's device that torsion view's mouse and keys move. Only the viewer builds it
// (BuildOptions::manual_devices); everything else refuses it naming the tool, before any mesh is
// read (this scene's cyl.node does not exist). A hand is taken with the viewer's M key instead.
TEST(ToolDevice, AManualDeviceMovesAToolInTheViewerOnly) {
  Result<SceneSpec> r = parse(sceneWithRigidBody(R"({"name": "probe", "mass": 0.02,
      "shape": {"sphere": {"radius": 0.01}},
      "device": {"type": "manual", "limits": {"max_force": 8}}})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const DeviceSpec& d = *r.value().rigid_bodies.at(0).device;
  EXPECT_EQ(d.kind, DeviceSpec::Kind::kManual);
  EXPECT_STREQ(toString(d.kind), "manual");
  EXPECT_EQ(d.max_force, 8);
  EXPECT_TRUE(failsWith(buildScene(r.value()),
                        {"s.json: device 'manual' of tool 'probe' is moved by the mouse and keys "
                         "of torsion view, which this run has not: use scripted, replay, "
                         "network, spacemouse or plugin"}));
  BuildOptions viewer;
  viewer.manual_devices = true;
  EXPECT_TRUE(failsWith(buildScene(r.value(), viewer), {"cyl.node"}))
      << "the viewer's build goes on to the (missing) mesh";

  EXPECT_TRUE(failsWith(parse(sceneWith(R"({"type": "manual"})")),
                        {"hands[0]", "type", "'manual' moves a tool", "M key takes a hand"}));

  Result<SceneSpec> scripted = parse(sceneWithRigidBody(
      R"({"name": "probe", "mass": 0.02, "shape": {"sphere": {"radius": 0.01}}})"));
  ASSERT_TRUE(scripted.ok()) << scripted.error().message;
  SceneSpec s = scripted.value();
  ASSERT_TRUE(applyDeviceOverride(s, "probe=manual").ok());
  EXPECT_EQ(s.rigid_bodies[0].device->kind, DeviceSpec::Kind::kManual);
  EXPECT_FALSE(s.rigid_bodies[0].device->loop.buttons_switch_force) << "a tool is always held";
  EXPECT_TRUE(failsWith(applyDeviceOverride(s, "probe=manual:5"),
                        {"--device 'probe=manual:5'", "manual takes no argument"}));
  EXPECT_TRUE(
      failsWith(applyDeviceOverride(s, "hand=manual"),
                {"--device 'hand=manual'", "manual moves a tool", "M key takes hand 'hand'"}));
  EXPECT_FALSE(s.hands[0].device.has_value());
}

TEST(ToolDevice, AGrasperIsABoxPalmWithADeviceAndJaws) {
  const std::string device = R"("device": {"type": "scripted", "trajectory": "p.json"})";
  Result<SceneSpec> r = parse(sceneWithRigidBody(
      R"({"name": "g", "mass": 0.5, "shape": {"box": {"half_extents": [0.2, 0.06, 0.02]}}, )" +
      device +
      R"(, "grasper": {"opening": 0.3, "closing_speed": 0.1, "grip_force": 30, "button": 2,
                       "jaw": {"half_extents": [0.015, 0.06, 0.07], "mass": 0.1, "friction": 0.9}}})"));
  ASSERT_TRUE(r.ok()) << r.error().message;
  const RigidBodySpec& g = r.value().rigid_bodies.at(0);
  ASSERT_TRUE(g.grasper.has_value());
  EXPECT_EQ(g.grasper->settings.opening, 0.3);
  EXPECT_EQ(g.grasper->settings.closing_speed, 0.1);
  EXPECT_EQ(g.grasper->settings.grip_force, 30);
  EXPECT_EQ(g.grasper->settings.button, 2);
  EXPECT_EQ(g.grasper->jaw_half_extents, Eigen::Vector3d(0.015, 0.06, 0.07));
  EXPECT_EQ(g.grasper->jaw_mass, 0.1);
  EXPECT_EQ(g.grasper->jaw_friction, 0.9);

  EXPECT_TRUE(failsWith(
      parse(sceneWithRigidBody(
          R"({"name": "g", "mass": 0.5, "shape": {"box": {"half_extents": [0.2, 0.06, 0.02]}},
                                   "grasper": {}})")),
      {"rigid_bodies[0]", "grasper", "give the body a 'device'"}));
  EXPECT_TRUE(failsWith(parse(sceneWithRigidBody(
                            R"({"name": "g", "mass": 0.5, "shape": {"sphere": {"radius": 0.1}}, )" +
                            device + R"(, "grasper": {}})")),
                        {"rigid_bodies[0]", "grasper", "a grasper's palm is a box"}));
  EXPECT_TRUE(failsWith(
      parse(sceneWithRigidBody(
          R"({"name": "g", "mass": 0.5, "shape": {"box": {"half_extents": [0.2, 0.06, 0.02]}}, )" +
          device + R"(, "grasper": {"grip_force": -1}})")),
      {"rigid_bodies[0]", "grasper", "grip_force", "must be > 0 N"}));
  EXPECT_TRUE(failsWith(
      parse(sceneWithRigidBody(
          R"({"name": "g", "mass": 0.5, "shape": {"box": {"half_extents": [0.2, 0.06, 0.02]}}, )" +
          device + R"(, "grasper": {"jaw": {"mass": 0}}})")),
      {"rigid_bodies[0]", "grasper", "jaw", "mass", "kg is outside"}));
}

}  // namespace device_parser_test
}  // namespace torsion::scene
