#include "device_parser.h"

#include <cstdlib>
#include <filesystem>

#include "torsion/device/packet_key.h"
#include "torsion/device/udp_socket.h"

namespace torsion::scene {

namespace {

std::string resolve(const std::string& path, const std::string& base_directory) {
  const std::filesystem::path p(path);
  return p.is_absolute() ? path : (std::filesystem::path(base_directory) / p).string();
}

double positive(const JsonObject& o, const std::string& key, double fallback,
                const std::string& unit) {
  const double v = o.number(key, fallback);
  if (!(v > 0)) o.fail(key, "must be > 0" + unit);
  return v;
}

double nonNegative(const JsonObject& o, const std::string& key, double fallback,
                   const std::string& unit) {
  const double v = o.number(key, fallback);
  if (!(v >= 0)) o.fail(key, "must be >= 0" + unit);
  return v;
}

// 127.0.0.0/8: only this machine can send there.
bool isLoopback(const std::string& host) {
  std::uint32_t address = 0;
  return device::parseIpv4(host, address) && (address >> 24) == 127;
}

void readNetwork(const JsonObject& d, DeviceSpec& spec, const std::string& base_directory) {
  spec.host = d.string("host", spec.host);
  std::uint32_t address = 0;
  if (!device::parseIpv4(spec.host, address))
    d.fail("host", "'" + spec.host + "' is not an IPv4 address");
  spec.port = d.integer("port", spec.port);
  if (spec.port < 0 || spec.port > 65535)
    d.fail("port", "must be in [0, 65535] (0: any free port)");
  spec.timeout = positive(d, "timeout", spec.timeout, " s");
  if (d.has("key_file")) spec.key_file = resolve(d.string("key_file"), base_directory);
}

void readSpaceMouse(const JsonObject& d, DeviceSpec& spec) {
  device::SpaceMouseSettings& s = spec.spacemouse;
  s.max_linear_speed = nonNegative(d, "max_linear_speed", s.max_linear_speed, " m/s");
  s.max_angular_speed = nonNegative(d, "max_angular_speed", s.max_angular_speed, " rad/s");
  s.full_scale = positive(d, "full_scale", s.full_scale, " counts");
  s.dead_zone = d.integer("dead_zone", s.dead_zone);
  if (s.dead_zone < 0 || s.dead_zone >= s.full_scale)
    d.fail("dead_zone", "must be in [0, full_scale)");
}

void readCoupling(const JsonObject& d, DeviceSpec& spec) {
  haptics::CouplingSettings& c = spec.coupling;
  const std::string rendering = d.string("rendering", "internal_force");
  if (rendering == "internal_force") {
    c.rendering = haptics::Rendering::kInternalForce;
  } else if (rendering == "frame_difference") {
    c.rendering = haptics::Rendering::kFrameDifference;
  } else {
    d.fail("rendering", "'" + rendering + "' is not one of: internal_force, frame_difference");
  }
  if (!d.has("coupling")) return;
  const JsonObject o = d.object("coupling");
  c.force_coefficient = nonNegative(o, "force_coefficient", c.force_coefficient, " m");
  c.torque_coefficient = nonNegative(o, "torque_coefficient", c.torque_coefficient, " m^3");
  c.stiffness_refresh_steps = o.integer("stiffness_refresh_steps", c.stiffness_refresh_steps);
  if (c.stiffness_refresh_steps < 0)
    o.fail("stiffness_refresh_steps", "must be >= 0 (0: no local stiffness)");
  c.stiffness_columns_per_step =
      o.integer("stiffness_columns_per_step", c.stiffness_columns_per_step);
  if (c.stiffness_columns_per_step < 1 || c.stiffness_columns_per_step > 6)
    o.fail("stiffness_columns_per_step", "must be in [1, 6]");
  c.lag_coupling = o.boolean("lag_coupling", c.lag_coupling);
  c.lag_damping_time = nonNegative(o, "lag_damping_time", c.lag_damping_time, " s");
  o.finish();
}

void readLoop(const JsonObject& d, DeviceSpec& spec) {
  device::HapticLoopSettings& l = spec.loop;
  l.rate_hz = d.number("rate_hz", l.rate_hz);
  if (!(l.rate_hz > 0 && l.rate_hz <= 20000)) d.fail("rate_hz", "must be in (0, 20000] Hz");
  l.step_blend_hz = nonNegative(d, "step_blend_hz", l.step_blend_hz, " Hz");
  if (d.has("damper")) {
    const JsonObject o = d.object("damper");
    l.damper.linear = nonNegative(o, "linear", l.damper.linear, " N s/m");
    l.damper.angular = nonNegative(o, "angular", l.damper.angular, " N m s/rad");
    o.finish();
  }
  if (d.has("passivity")) {
    const JsonObject o = d.object("passivity");
    device::PassivitySettings& p = l.passivity;
    p.enabled = o.boolean("enabled", p.enabled);
    p.length_scale = positive(o, "length_scale", p.length_scale, " m");
    p.rate_limited = o.boolean("rate_limited", p.rate_limited);
    p.speed_hold_time = positive(o, "speed_hold_time", p.speed_hold_time, " s");
    p.speed_margin = positive(o, "speed_margin", p.speed_margin, "");
    p.energy_tolerance = nonNegative(o, "energy_tolerance", p.energy_tolerance, " J");
    p.misprediction_margin = nonNegative(o, "misprediction_margin", p.misprediction_margin, "");
    o.finish();
  }
  if (d.has("safety")) {
    const JsonObject o = d.object("safety");
    device::SafetySettings& s = l.safety;
    s.max_force_rate = positive(o, "max_force_rate", s.max_force_rate, " N/s");
    s.max_torque_rate = positive(o, "max_torque_rate", s.max_torque_rate, " N m/s");
    s.stale_after = positive(o, "stale_after", s.stale_after, " s");
    s.fade_time = positive(o, "fade_time", s.fade_time, " s");
    o.finish();
  }
}

// What every device entry has: its type and the type's keys, playback speed, limits and mapping.
DeviceSpec readDeviceKind(const JsonObject& d, const std::string& base_directory) {
  DeviceSpec spec;
  const std::string type = d.string("type");
  if (type == "scripted") {
    spec.kind = DeviceSpec::Kind::kScripted;
    spec.file = resolve(d.string("trajectory"), base_directory);
  } else if (type == "replay") {
    spec.kind = DeviceSpec::Kind::kReplay;
    spec.file = resolve(d.string("log"), base_directory);
  } else if (type == "network") {
    spec.kind = DeviceSpec::Kind::kNetwork;
    readNetwork(d, spec, base_directory);
  } else if (type == "spacemouse") {
    spec.kind = DeviceSpec::Kind::kSpaceMouse;
    readSpaceMouse(d, spec);
  } else if (type == "plugin") {
    spec.kind = DeviceSpec::Kind::kPlugin;
    spec.file = resolve(d.string("library"), base_directory);
    spec.config = d.string("config", "");
    spec.isolated = d.boolean("isolated", spec.isolated);
  } else if (type == "manual") {
    spec.kind = DeviceSpec::Kind::kManual;
  } else {
    d.fail("type",
           "'" + type + "' is not one of: scripted, replay, network, spacemouse, plugin, manual");
  }
  if (spec.kind == DeviceSpec::Kind::kScripted || spec.kind == DeviceSpec::Kind::kReplay)
    spec.speed = positive(d, "speed", spec.speed, " (playback speed)");
  if (spec.kind != DeviceSpec::Kind::kSpaceMouse && d.has("limits")) {
    // A SpaceMouse has no motors: it takes no force limits.
    const JsonObject o = d.object("limits");
    spec.max_force = nonNegative(o, "max_force", spec.max_force, " N");
    spec.max_torque = nonNegative(o, "max_torque", spec.max_torque, " N m");
    o.finish();
  }
  if (d.has("mapping")) {
    const JsonObject o = d.object("mapping");
    spec.position_scale =
        positive(o, "position_scale", spec.position_scale, " (world m per device m)");
    spec.force_scale = nonNegative(o, "force_scale", spec.force_scale, " (device N per world N)");
    spec.torque_scale = nonNegative(o, "torque_scale", spec.torque_scale, "");
    o.finish();
  }
  return spec;
}

// A tool's "coupling": the virtual coupling's spring and damper (tool_coupling.h).
void readToolCoupling(const JsonObject& d, DeviceSpec& spec) {
  if (d.has("rendering"))
    d.fail("rendering", "a tool renders its coupling's force; 'rendering' is a hand's key");
  if (!d.has("coupling")) return;
  const JsonObject o = d.object("coupling");
  haptics::ToolCouplingSettings& t = spec.tool;
  t.stiffness = positive(o, "stiffness", t.stiffness, " N/m");
  t.angular_stiffness = positive(o, "angular_stiffness", t.angular_stiffness, " N m/rad");
  t.damping_ratio = nonNegative(o, "damping_ratio", t.damping_ratio, " (1: critical)");
  t.max_force = positive(o, "max_force", t.max_force, " N");
  t.max_torque = positive(o, "max_torque", t.max_torque, " N m");
  t.feel_weight = o.boolean("feel_weight", t.feel_weight);
  t.contact_stiffness_refresh_steps =
      o.integer("contact_stiffness_refresh_steps", t.contact_stiffness_refresh_steps);
  if (t.contact_stiffness_refresh_steps < 0)
    o.fail("contact_stiffness_refresh_steps", "must be >= 0 (0: rigid contacts only)");
  o.finish();
  if (Status ok = t.validate(); !ok) d.fail("coupling", ok.error().message);
}

// A key file in the scene, or a key in the environment (device_factory.cpp loads it; a key that
// fails to load stops the run there).
bool authenticated(const DeviceSpec& spec) {
  const char* file = std::getenv(device::kKeyFileVariable);
  const char* secret = std::getenv(device::kKeyVariable);
  return !spec.key_file.empty() || (file && *file) || (secret && *secret);
}

}  // namespace

const char* toString(DeviceSpec::Kind kind) {
  switch (kind) {
    case DeviceSpec::Kind::kScripted:
      return "scripted";
    case DeviceSpec::Kind::kReplay:
      return "replay";
    case DeviceSpec::Kind::kNetwork:
      return "network";
    case DeviceSpec::Kind::kSpaceMouse:
      return "spacemouse";
    case DeviceSpec::Kind::kPlugin:
      return "plugin";
    case DeviceSpec::Kind::kManual:
      return "manual";
  }
  return "?";
}

const char* toString(HapticsMode mode) {
  switch (mode) {
    case HapticsMode::kAuto:
      return "auto";
    case HapticsMode::kLockstep:
      return "lockstep";
    case HapticsMode::kThreaded:
      return "threaded";
  }
  return "?";
}

DeviceSpec readDevice(const JsonObject& hand, const std::string& base_directory) {
  for (const char* scripted : {"keyframes", "motion", "grab_at", "release_at"}) {
    if (hand.has(scripted)) {
      hand.fail(scripted,
                "a hand with a device is moved by the device and grabs and releases with its "
                "buttons 1 and 2; remove this key (the hand's frame is where the device's zero "
                "pose sits)");
    }
  }
  const JsonObject d = hand.object("device");
  DeviceSpec spec = readDeviceKind(d, base_directory);
  if (spec.kind == DeviceSpec::Kind::kManual) {
    d.fail("type",
           "'manual' moves a tool (a rigid body's device); torsion view's M key takes a hand");
  }
  readCoupling(d, spec);
  readLoop(d, spec);
  d.finish();
  return spec;
}

DeviceSpec readToolDevice(const JsonObject& body, const std::string& base_directory) {
  const JsonObject d = body.object("device");
  DeviceSpec spec = readDeviceKind(d, base_directory);
  readToolCoupling(d, spec);
  readLoop(d, spec);
  spec.loop.buttons_switch_force = false;  // a tool is always held
  d.finish();
  return spec;
}

Status applyDeviceOverride(SceneSpec& scene, const std::string& text) {
  const std::string flag = "--device '" + text + "'";
  const size_t equals = text.find('=');
  if (equals == std::string::npos || equals == 0) {
    return Error{flag +
                 ": expected NAME=TYPE[:ARG] (NAME a hand or a dynamic rigid body), e.g. "
                 "hand=network:5750 or probe=replay:log.csv"};
  }
  const std::string name = text.substr(0, equals);
  HandSpec* hand = nullptr;
  RigidBodySpec* tool = nullptr;
  std::string names;
  for (HandSpec& h : scene.hands) {
    if (h.name == name) hand = &h;
    names += (names.empty() ? "hands: '" : ", '") + h.name + "'";
  }
  std::string dynamic_names;
  for (RigidBodySpec& r : scene.rigid_bodies) {
    if (r.mass <= 0) continue;
    if (r.name == name && !hand) tool = &r;
    dynamic_names += (dynamic_names.empty() ? "dynamic rigid bodies: '" : ", '") + r.name + "'";
  }
  if (!hand && !tool) {
    std::string known = names;
    if (!dynamic_names.empty()) known += (known.empty() ? "" : "; ") + dynamic_names;
    return Error{flag + ": the scene has no hand or dynamic rigid body named '" + name + "'" +
                 (known.empty() ? std::string(" (it has neither)") : " (" + known + ")")};
  }
  const std::optional<DeviceSpec>& current = hand ? hand->device : tool->device;
  const std::string value = text.substr(equals + 1);
  const size_t colon = value.find(':');
  const std::string type = value.substr(0, colon);
  const std::string arg = colon == std::string::npos ? "" : value.substr(colon + 1);

  DeviceSpec spec = current ? *current : DeviceSpec{};
  if (tool && !current) spec.loop.buttons_switch_force = false;  // a tool is always held
  spec.file.clear();
  if (type == "scripted" || type == "replay") {
    if (arg.empty()) return Error{flag + ": " + type + " needs a file: " + type + ":FILE"};
    spec.kind = type == "scripted" ? DeviceSpec::Kind::kScripted : DeviceSpec::Kind::kReplay;
    spec.file = arg;
  } else if (type == "network") {
    spec.kind = DeviceSpec::Kind::kNetwork;
    std::string port = arg;
    const size_t host_end = arg.rfind(':');
    if (host_end != std::string::npos) {
      spec.host = arg.substr(0, host_end);
      port = arg.substr(host_end + 1);
      std::uint32_t address = 0;
      if (!device::parseIpv4(spec.host, address))
        return Error{flag + ": '" + spec.host + "' is not an IPv4 address"};
    }
    if (!port.empty()) {
      size_t used = 0;
      int p = -1;
      try {
        p = std::stoi(port, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != port.size() || p < 0 || p > 65535)
        return Error{flag + ": port '" + port + "' is not a number in [0, 65535]"};
      spec.port = p;
    }
  } else if (type == "spacemouse") {
    if (!arg.empty()) return Error{flag + ": spacemouse takes no argument"};
    spec.kind = DeviceSpec::Kind::kSpaceMouse;
  } else if (type == "plugin" || type == "plugin-inproc") {
    // plugin: in the device host process; plugin-inproc: in this process (its crash ends the run)
    const size_t config = arg.find(':');
    spec.kind = DeviceSpec::Kind::kPlugin;
    spec.isolated = type == "plugin";
    spec.file = arg.substr(0, config);
    spec.config = config == std::string::npos ? "" : arg.substr(config + 1);
    if (spec.file.empty())
      return Error{flag + ": " + type + " needs a shared library: " + type + ":LIBRARY[:CONFIG]"};
  } else if (type == "manual") {
    if (!arg.empty()) return Error{flag + ": manual takes no argument"};
    spec.kind = DeviceSpec::Kind::kManual;
  } else {
    return Error{flag + ": unknown device type '" + type +
                 "' (known: scripted, replay, network, spacemouse, plugin, plugin-inproc, "
                 "manual)"};
  }
  if (tool) {
    tool->device = spec;
    return Ok{};
  }
  if (spec.kind == DeviceSpec::Kind::kManual) {
    return Error{flag +
                 ": manual moves a tool (a dynamic rigid body); torsion view's M key takes "
                 "hand '" +
                 name + "'"};
  }
  if (!hand->keyframes.empty()) {  // the scripted motion gives way; its start is the anchor
    hand->initial = hand->keyframes.front().second;
    hand->keyframes.clear();
  }
  hand->motion = MotionSpec{};
  hand->device = spec;
  return Ok{};
}

Result<HapticsMode> parseHapticsMode(const std::string& text) {
  if (text == "lockstep") return HapticsMode::kLockstep;
  if (text == "threaded") return HapticsMode::kThreaded;
  return Error{"--haptics '" + text + "': expected lockstep or threaded"};
}

Status applyDeviceOverrides(SceneSpec& scene, const DeviceOverrides& overrides) {
  for (const std::string& d : overrides.devices) {
    if (Status applied = applyDeviceOverride(scene, d); !applied) return applied;
  }
  if (!overrides.haptics.empty()) {
    Result<HapticsMode> mode = parseHapticsMode(overrides.haptics);
    if (!mode) return mode.error();
    scene.haptics_mode = mode.value();
  }
  // Below the loops' own priority (80), so that they still preempt the simulation.
  if (overrides.simulation_priority < 0 || overrides.simulation_priority > 79) {
    return Error{"--sim-priority: " + std::to_string(overrides.simulation_priority) +
                 " is not in [0, 79] (the haptic loops run at 80 and must preempt the "
                 "simulation)"};
  }
  scene.simulation_priority = overrides.simulation_priority;
  if (!overrides.allow_remote_devices) {
    auto exposed = [](const std::optional<DeviceSpec>& d) {
      return d && d->kind == DeviceSpec::Kind::kNetwork && !isLoopback(d->host) &&
             !authenticated(*d);
    };
    auto refuse = [&scene](const std::string& entry, const std::string& what,
                           const std::string& host) {
      return Error{scene.file + ": " + entry + ": device host " + host +
                   " is not loopback: anyone who can reach that port could drive the " + what +
                   " (the packets are not authenticated); give the device a key_file (or set " +
                   device::kKeyFileVariable +
                   ", docs/haptic-devices.md), or pass "
                   "--allow-remote-device to listen there unauthenticated"};
    };
    for (size_t h = 0; h < scene.hands.size(); ++h) {
      const HandSpec& hand = scene.hands[h];
      if (exposed(hand.device))
        return refuse("hands[" + std::to_string(h) + "] '" + hand.name + "'", "hand",
                      hand.device->host);
    }
    for (size_t r = 0; r < scene.rigid_bodies.size(); ++r) {
      const RigidBodySpec& body = scene.rigid_bodies[r];
      if (exposed(body.device))
        return refuse("rigid_bodies[" + std::to_string(r) + "] '" + body.name + "'", "tool",
                      body.device->host);
    }
  }
  return Ok{};
}

std::vector<std::string> remoteDeviceWarnings(const SceneSpec& scene) {
  std::vector<std::string> warnings;
  auto warn = [&warnings](const std::string& holder, const std::optional<DeviceSpec>& d) {
    if (!d || d->kind != DeviceSpec::Kind::kNetwork || isLoopback(d->host)) return;
    warnings.push_back(
        holder + ": the network device listens on " + d->host +
        (authenticated(*d)
             ? ", outside loopback: only peers holding the shared key are heard; the packets "
               "are signed, not encrypted (docs/haptic-devices.md)"
             : ", outside loopback: its first peer is bound, unauthenticated "
               "(docs/haptic-devices.md)"));
  };
  for (const HandSpec& hand : scene.hands)
    warn("hand '" + hand.name + "'", hand.device);
  for (const RigidBodySpec& body : scene.rigid_bodies)
    warn("tool '" + body.name + "'", body.device);
  return warnings;
}

}  // namespace torsion::scene
