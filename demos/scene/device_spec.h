#pragma once
// A haptic device as a scene names it (docs/scene-format.md, "hands[].device" and
// "rigid_bodies[].device"), plain data with paths resolved; device_factory opens it,
// scene_haptics wires it to what it holds. A hand with a device has no scripted motion: its
// `frame` is where the device's zero pose sits in the world, and the device's buttons grab and
// release (the report's section 5.4). A rigid body with a device is a tool: the device's zero
// pose sits at the body's starting pose, and a virtual coupling pulls the body toward the device
// (torsion/haptics/tool_coupling.h).

#include <string>

#include "torsion/device/haptic_loop.h"
#include "torsion/device/spacemouse_integrator.h"
#include "torsion/haptics/grasper_coupling.h"
#include "torsion/haptics/hand_coupling.h"
#include "torsion/haptics/tool_coupling.h"

namespace torsion::scene {

struct DeviceSpec {
  /// kManual: moved by `torsion view`'s mouse and keys (device/manual_device.h); only the viewer
  /// has them, so buildScene refuses it unless BuildOptions::manual_devices says otherwise.
  enum class Kind {
    kScripted,
    kReplay,
    kNetwork,
    kSpaceMouse,
    kPlugin,
    kManual
  } kind = Kind::kScripted;
  std::string file;    ///< scripted: trajectory JSON; replay: loop log CSV; plugin: shared library
  std::string config;  ///< plugin: the text handed to the plug-in's open()
  /// plugin: run it in its own process (torsion_device_host), so that its crash ends only that
  /// process; false: in Torsion's process (a little faster; its crash ends the run)
  bool isolated = true;
  double speed = 1;                ///< scripted, replay: playback speed (2: twice as fast)
  std::string host = "127.0.0.1";  ///< network: IPv4 address the poses arrive on
  int port = 5750;                 ///< network: UDP port
  double timeout = 0.05;           ///< network: s without a pose before the device is dead
  /// network: file of the shared packet key (resolved; empty: TORSION_HAPTIC_KEY_FILE or
  /// TORSION_HAPTIC_KEY from the environment, else unauthenticated packets)
  std::string key_file;
  device::SpaceMouseSettings spacemouse;
  double max_force = 30;               ///< N, the device's limit (a plug-in: at most its own)
  double max_torque = 3;               ///< N m
  double position_scale = 1;           ///< world m per device m
  double force_scale = 1;              ///< device N per world N
  double torque_scale = 1;             ///< device N m per world N m
  haptics::CouplingSettings coupling;  ///< a hand's
  haptics::ToolCouplingSettings tool;  ///< a tool's
  device::HapticLoopSettings loop;     ///< rate, damper, safety (log capacity set by the run)
};

const char* toString(DeviceSpec::Kind kind);

/// How the haptic loops of a scene run. Auto: lockstep unless a device lives in wall-clock time
/// (network, SpaceMouse), then threaded.
///   lockstep: every loop ticks on the simulated clock, one step's worth of ticks before each
///             step; deterministic (tests, regression, plots);
///   threaded: every loop on its own thread at its rate in wall-clock time, the simulation paced
///             so it never runs ahead of wall-clock time.
enum class HapticsMode { kAuto, kLockstep, kThreaded };

const char* toString(HapticsMode mode);

}  // namespace torsion::scene
