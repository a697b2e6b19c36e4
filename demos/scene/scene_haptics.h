#pragma once
// The haptic side of a scene: for every hand and every tool (a rigid body) with a device, the
// open device, its 1 kHz HapticLoop and the coupling between them (HandCoupling, ToolCoupling),
// run by one HapticRuntime in lockstep or threaded mode (device_spec.h). buildScene attaches it;
// stepScene steps a scene with or without it.
//
//   Threads (threaded mode) | may touch
//   simulation (the caller of stepScene / finish) | the world, hands, couplings; the loops'
//       buffers as reader of commands and writer of wrenches
//   one haptic thread per device (hand or tool) | its device; its loop's buffers as the other side
// In lockstep mode everything runs on the caller's thread.

#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "scene_builder.h"
#include "torsion/device/haptic_device.h"
#include "torsion/device/haptic_loop.h"
#include "torsion/device/manual_device.h"
#include "torsion/haptics/hand_coupling.h"
#include "torsion/haptics/haptic_runtime.h"

namespace torsion::scene {

class SceneHaptics {
 public:
  /// Opens the devices of the scene's device hands and tools and couples them. Errors name the
  /// hand or the rigid body.
  static Result<std::unique_ptr<SceneHaptics>> attach(BuiltScene& scene);
  ~SceneHaptics();

  HapticsMode mode() const { return mode_; }
  /// Sizes the loops' logs for a run of `steps` steps (before the first step).
  void prepareRun(int steps);
  /// One step: lockstep ticks the loops over it first; threaded starts the loops' threads on
  /// the first call and paces the simulation to wall-clock time.
  WorldStepReport step();
  /// Threaded: starts the threads if needed and waits until the coming step is due in
  /// wall-clock time (step() does it too; call it first to keep the wait out of a step's
  /// timing). Lockstep: nothing.
  void pace();
  /// Stops the threads (zero wrench to every device), writes haptic_<name>.csv per device (hand
  /// or tool) into `directory` and returns per-device statistics for summary.json.
  Result<nlohmann::json> finish(const std::string& directory);

  /// The names of the logs finish() writes, "haptic_<name>.csv" per device.
  std::vector<std::string> logFileNames() const;

  /// One line per device: "hand 'h': device scripted(f.json), lockstep haptic loop at 1000 Hz"
  /// ("tool 'probe': ..." for a tool).
  std::vector<std::string> describe() const;
  /// The wrench the device of hand or tool `name` renders (world frame, last step); nullopt when
  /// nothing of that name has a device.
  std::optional<Wrench> deviceWrench(const std::string& name) const;
  /// Each tool's name and the wrench its device renders (world frame, last step).
  std::vector<std::pair<std::string, Wrench>> toolWrenches() const;
  /// The runtime's warnings, and a refused --sim-priority.
  std::vector<std::string> warnings() const;

  /// A tool as the viewer reports it (simulation thread).
  struct ToolState {
    std::string name;
    DeviceSpec::Kind kind = DeviceSpec::Kind::kScripted;
    Frame goal;                     ///< the device's frame in the world, where the tool is pulled
    std::optional<double> jaw_gap;  ///< m, between a grasper's jaws
  };
  /// Each tool with a device, in the scene's order.
  std::vector<ToolState> tools() const;

  /// The tool whose manual device the viewer moves: set `device`'s pose to
  /// mapping.toDevice(wanted world frame) and its buttons (a grasper closes while button 1 is
  /// held). Valid while this SceneHaptics lives.
  struct ManualTool {
    std::string name;
    device::ManualDevice* device = nullptr;
    haptics::DeviceMapping mapping;
    bool grasper = false;
  };
  /// The first tool with a manual device; nullopt when none has one.
  std::optional<ManualTool> manualTool() const;

 private:
  struct Channel {
    std::string name;  ///< the hand's or the tool's
    bool tool = false;
    DeviceSpec::Kind kind = DeviceSpec::Kind::kScripted;
    haptics::DeviceMapping mapping;
    std::unique_ptr<device::HapticDevice> device;
    std::unique_ptr<haptics::DeviceCoupling> coupling;
    std::unique_ptr<device::HapticLoop> loop;
    double rate_hz = 1000;
  };
  SceneHaptics() = default;
  /// `spec`'s device, opened, and its loop (the coupling is the caller's); `entry` names it in
  /// errors. In lockstep every loop must tick at the rate of the first (`first_rate_hz`, 0: none
  /// yet).
  Result<Channel> openChannel(const DeviceSpec& spec, const std::string& entry,
                              double first_rate_hz) const;
  nlohmann::json statistics(const Channel& channel) const;

  HapticsMode mode_ = HapticsMode::kLockstep;
  double dt_ = 0.01;
  std::vector<Channel> channels_;
  std::unique_ptr<haptics::HapticRuntime> runtime_;
  int simulation_priority_ = 0;        // asked for (--sim-priority)
  bool simulation_real_time_ = false;  // granted when the threads started (stop restores it)
  bool threads_started_ = false;
  bool finished_ = false;
};

/// One step of a built scene: scripted hands are driven (driveHands), then the world steps,
/// through the haptic runtime when the scene has device hands. Errors: a scripted grab missed.
Result<WorldStepReport> stepScene(BuiltScene& scene);

}  // namespace torsion::scene
