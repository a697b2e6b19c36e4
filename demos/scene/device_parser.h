#pragma once
// The `device` entry of a scene hand or rigid body (a tool), and the CLI's `--device
// NAME=TYPE[:ARG]` override.

#include <string>
#include <vector>

#include "json_reader.h"
#include "scene_spec.h"
#include "torsion/result.h"

namespace torsion::scene {

/// Reads hand.device (`hand` is the hand's object; it must not also script a motion or grab
/// times). Relative paths are resolved against `base_directory`. Throws JsonFault naming the key.
DeviceSpec readDevice(const JsonObject& hand, const std::string& base_directory);
/// Reads rigid_body.device: the same device keys, with a tool's "coupling" (stiffness,
/// angular_stiffness, damping_ratio, max_force, max_torque, feel_weight) and no "rendering".
DeviceSpec readToolDevice(const JsonObject& body, const std::string& base_directory);

/// Applies `--device NAME=TYPE[:ARG]`: scripted:FILE, replay:FILE, network[:PORT] or
/// network:HOST:PORT, spacemouse, plugin:LIBRARY[:CONFIG] (CONFIG: the rest, colons included),
/// manual (torsion view's mouse and keys).
/// NAME is a hand, else a dynamic rigid body, which becomes a tool. A hand that had a scripted
/// motion keeps its starting frame as the device's anchor; one that had a device keeps its
/// mapping, limits and coupling, and so does a tool. FILE is relative to the working directory.
Status applyDeviceOverride(SceneSpec& scene, const std::string& text);

/// "lockstep" or "threaded" (the CLI's --haptics).
Result<HapticsMode> parseHapticsMode(const std::string& text);

/// The command line's device choices, the same for `torsion run` and `torsion view`.
struct DeviceOverrides {
  std::vector<std::string> devices;  ///< `--device NAME=TYPE[:ARG]`, repeatable
  std::string haptics;               ///< `--haptics lockstep|threaded`; empty: the default
  /// `--allow-remote-device`: a network device may listen on an address other than loopback.
  bool allow_remote_devices = false;
  /// `--sim-priority N`: SCHED_FIFO priority (1-79) of the stepping thread while threaded loops
  /// run; 0: the thread's own policy.
  int simulation_priority = 0;
};

/// Applies every --device (applyDeviceOverride), then --haptics, to `scene`; the first fault
/// is the error. A network device on a host outside 127.0.0.0/8 is an error unless its packets
/// are authenticated (a key_file, or a key in the environment) or `allow_remote_devices`
/// (docs/haptic-devices.md).
Status applyDeviceOverrides(SceneSpec& scene, const DeviceOverrides& overrides);

/// One warning per network device listening outside loopback (after applyDeviceOverrides).
std::vector<std::string> remoteDeviceWarnings(const SceneSpec& scene);

}  // namespace torsion::scene
