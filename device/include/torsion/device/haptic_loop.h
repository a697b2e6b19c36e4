#pragma once
// The haptic loop: one thread at 1 kHz (absolute deadlines on the monotonic clock, so periods do
// not drift), each tick:
//   1. read the device (pose, buttons, alive); a reading the loop refuses (reading_check.h)
//      enters none of its state: the last accepted one stands in for it for at most
//      reading.hold_time, then the device counts as dead;
//   2. buttons, as the report's section 5.4: button 1 pressed -> a grab request and force
//      enabled; button 2 pressed -> a release request and force disabled;
//   3. hand the simulation a HandCommand (lock-free, commands());
//   4. take the newest SimulationWrench (lock-free, wrenches()) and render the local model
//      W_sim + K_h dpose - B twist (local_wrench_model.h), a new step's change blended in while
//      the step carries K_h (step_blend.h, step_blend_hz);
//   5. pass the wrench through the SafetyFilter, let the passivity controller (passivity.h) take
//      back the generated energy (the dead-beat damper on top of the filter's output, or the
//      rate-limited controller within the filter's rate limit), hand the result back to the
//      filter, whose rate limit is always the last stage, write it to the device and book its
//      energy at the port;
//   6. append a row to the in-memory log (no I/O on this thread; writeLog after stop()).
//
// Threads: tick() runs on the loop thread (or on a test's thread with a fake clock, never both);
// commands() is read and wrenches() written by exactly one simulation thread; stats() from any.

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "torsion/device/haptic_device.h"
#include "torsion/device/local_wrench_model.h"
#include "torsion/device/passivity.h"
#include "torsion/device/reading_check.h"
#include "torsion/device/step_blend.h"
#include "torsion/device/triple_buffer.h"
#include "torsion/device/wrench_safety.h"

namespace torsion::device {

struct HapticLoopSettings {
  double rate_hz = 1000;  ///< ticks per second
  SafetySettings safety;
  ReadingCheck reading;  ///< which device readings the loop takes (reading_check.h)
  CouplingDamper damper;
  PassivitySettings passivity;  ///< time-domain passivity observer and controller (on)
  double twist_cutoff_hz = 50;  ///< low-pass of the velocity the damper sees
  /// Hz: each new simulation step's change of the local model is blended in through a
  /// first-order low-pass of this cutoff instead of stepping (step_blend.h), while the step
  /// carries a local stiffness K_h (without one the whole rendering would be low-passed); 0:
  /// off. 8 by default: a stiff body under delay is felt as without delay (docs/haptics.md).
  double step_blend_hz = 8;
  /// true: button 1 turns the force on and button 2 off (a hand grabs and releases); false: the
  /// force is on from the first tick and buttons only count (a tool is always held).
  bool buttons_switch_force = true;
  std::size_t log_capacity = 0;  ///< rows kept in memory (one per tick); 0: no log
  /// SCHED_FIFO priority (1-99) the loop's thread asks for; it keeps the default policy,
  /// silently, when that is not permitted (LoopStats::realtime says which). 0: do not ask.
  int realtime_priority = 80;

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

/// One tick as logged (docs/haptics.md lists the CSV columns).
struct LoopLogRow {
  std::uint64_t tick = 0;
  double time = 0;      ///< s, loop clock
  double period = 0;    ///< s since the previous tick
  double lateness = 0;  ///< s the tick started after its deadline
  Pose pose;
  std::uint32_t buttons = 0;
  bool alive = false;
  Wrench output;     ///< what was written to the device
  Wrench simulated;  ///< the simulation's wrench the local model started from
  std::uint64_t sim_step = 0;
  double wrench_age = 0;  ///< s since that simulation wrench arrived
  /// s, age of the newest information in the rendered wrench: with a local stiffness, the age of
  /// the device pose the prediction used (read this tick); without, now minus the time of the
  /// pose the simulation step used (HandCommand::time). 0 before the first publication.
  double information_age = 0;
  std::int64_t pose_lag_ticks = -1;  ///< ticks since the pose the simulation used (-1: none)
  bool grabbed = false;
  bool fresh = false;
  double port_energy = 0;  ///< J, E_obs after this tick (passivity.h; <= 0 when passive)
  double pc_alpha = 0;     ///< N s/m, the passivity controller's damping this tick
};

struct LoopStats {
  std::atomic<std::uint64_t> ticks{0};
  std::atomic<std::uint64_t> overruns{0};     ///< ticks that started a full period late
  std::atomic<std::uint64_t> log_dropped{0};  ///< rows not logged: capacity reached
  std::atomic<std::uint64_t> nonfinite{0};    ///< rendered wrenches with NaN/inf (zeroed)
  std::atomic<std::uint64_t> refused{0};      ///< device readings refused (reading_check.h)
  std::atomic<std::uint64_t> saturated{0};    ///< ticks whose wrench exceeded a device limit
  std::atomic<bool> realtime{false};          ///< the thread runs under SCHED_FIFO
  std::atomic<std::uint64_t> pc_active{0};    ///< ticks the passivity controller acted
  std::atomic<double> pc_dissipated{0};       ///< J the passivity controller took out
  std::atomic<double> max_port_energy{0};     ///< J, largest E_obs (> 0: energy was generated)
};

class HapticLoop {
 public:
  HapticLoop(HapticDevice& device, const HapticLoopSettings& settings);
  ~HapticLoop();
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  /// The simulation reads device commands here...
  TripleBuffer<HandCommand>& commands() { return commands_; }
  /// ...and publishes its wrenches here.
  TripleBuffer<SimulationWrench>& wrenches() { return wrenches_; }

  /// One tick at loop time `now` (s). `deadline` is when it was due (for the log).
  void tick(double now, double deadline);
  void tick(double now) { tick(now, now); }

  /// Runs tick() on its own thread at rate_hz until stop(). The loop clock is seconds of the
  /// monotonic clock since start().
  void start();
  /// Stops the thread and writes a zero wrench to the device.
  void stop();
  bool running() const { return thread_.joinable(); }

  const LoopStats& stats() const { return stats_; }
  /// The log so far; only while the loop is not running (or from the ticking thread).
  const std::vector<LoopLogRow>& log() const { return log_; }
  /// Keeps at most `rows` log rows (reserved now); only while the loop is not running.
  void setLogCapacity(std::size_t rows);
  /// Writes the log as CSV, whole or not at all (file_io.h); false when the file cannot be
  /// written, with the reason ("<path>: cannot write: <strerror>") in *error when given.
  bool writeLog(const std::string& path, std::string* error = nullptr) const;
  const Wrench& lastOutput() const { return safety_.output(); }
  bool forceEnabled() const { return force_enabled_; }
  bool passivityEnabled() const { return settings_.passivity.enabled; }

 private:
  void run();
  /// This tick's device reading: the device's own when the checks accept it, else the last
  /// accepted one (alive for at most reading.hold_time of refusals). *accepted says which.
  DeviceSample takeReading(double now, bool* accepted);

  HapticDevice& device_;
  HapticLoopSettings settings_;
  DeviceLimits limits_;
  SafetyFilter safety_;
  TwistEstimator twist_;
  PassivityController passivity_;
  DeviceSample accepted_;   // the last accepted reading (its time: the loop clock's when read)
  double accepted_at_ = 0;  // s, loop clock of the tick that accepted it
  bool have_accepted_ = false;
  double refused_since_ = -1;  // s, first tick of the current run of refusals; < 0: none
  TripleBuffer<HandCommand> commands_;
  TripleBuffer<SimulationWrench> wrenches_;
  LoopStats stats_;
  std::vector<LoopLogRow> log_;

  std::uint64_t tick_ = 0;
  double previous_time_ = 0;
  bool have_previous_ = false;
  std::uint32_t previous_buttons_ = 0;
  bool force_enabled_ = false;
  std::uint32_t grab_requests_ = 0;
  std::uint32_t release_requests_ = 0;
  SimulationWrench simulated_;
  StepBlend blend_;
  double last_fresh_time_ = -1e300;

  std::thread thread_;
  std::atomic<bool> stop_requested_{false};
};

}  // namespace torsion::device
