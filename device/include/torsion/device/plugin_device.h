#pragma once
// A haptic device in a shared library, loaded at run time through the C ABI of plugin_abi.h
// (`--device HAND=plugin:/path/libdev.so[:CONFIG]`, docs/haptic-devices.md).
//
// Where the plug-in runs:
//   - isolated (the default): in a process of its own, torsion_device_host (`host_program`),
//     reached through shared memory. A plug-in that crashes (segfault, abort) ends only that
//     process: the device reaps it, reports how it ended (hostExit(), printed once as a warning)
//     and is dead from then on, so the loop fades the output to zero and the run goes on;
//   - in process (`isolated = false`): on a worker thread of Torsion's process, a little faster;
//     a crash in the plug-in ends Torsion.
//
// The loader trusts nothing the library returns, wherever it runs:
//   - open: the checks of plugin_library.h (entry symbol, ABI version, function table, open(),
//     info()); otherwise open() fails with a message naming the library and the fault;
//   - every tick: read() waits for the plug-in only until `read_deadline` (an answer that comes
//     later, to an earlier tick, is not used); a reading that is late, failed (non-zero return),
//     non-finite or has a non-unit quaternion is not used: the device keeps its last good reading
//     for at most `hold_time` (a late tick on a busy machine does not fade the force), then
//     reports itself dead, so the haptic loop's safety filter fades the output to zero exactly as
//     for a built-in device that stopped answering. Each kind of fault is counted (stats()).
//   - a read() still inside the plug-in after `hung_timeout` is hung: later ticks do not wait for
//     it (the device is dead until it returns), and a warning names the plug-in once;
//   - open() that does not return within `start_timeout` (in process: on a thread of its own;
//     isolated: in the host) fails, naming the plug-in; the thread is abandoned (or the host
//     killed);
//   - at destruction: the last (zero) wrench, then close(). A plug-in that does not return within
//     `close_timeout` is, isolated, killed with its host; in process, its thread is detached and
//     the library stays loaded (unloading code that may still run would crash), and the run goes
//     on.
//
// Threads: read(), write() from the haptic loop's thread only (as every HapticDevice); stats(),
// hostExit() from any thread. The plug-in itself is only ever called from one thread (the worker
// or the host's), one call at a time. open() from a thread that outlives the device: the host is
// killed when the thread that started it ends (PR_SET_PDEATHSIG).

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "torsion/device/haptic_device.h"
#include "torsion/device/loaded.h"

namespace torsion::device {

class PluginTransport;  // where the plug-in's calls run (plugin_transport.h, private)

struct PluginDeviceSettings {
  std::string library;            ///< path of the shared library (dlopen)
  std::string config;             ///< text handed to the plug-in's open(), maybe empty
  double read_deadline = 0.0005;  ///< s the loop waits for one read() of the plug-in
  double hold_time = 0.005;       ///< s a good reading may stand in for late or bad ones
  double close_timeout = 1.0;     ///< s to wait for the plug-in's last calls at destruction
  /// Run the plug-in in its own process (torsion_device_host) rather than in Torsion's.
  bool isolated = true;
  /// isolated: path of the torsion_device_host program (built and installed in
  /// <libdir>/torsion, beside the plug-ins' directory).
  std::string host_program;
  /// s for the plug-in's open() to return (isolated: for the host to start and open it); a
  /// plug-in that takes longer is abandoned and open() fails, naming it.
  double start_timeout = 10.0;
  /// s a read() may stay inside the plug-in before it counts as hung: later ticks then stop
  /// waiting for it (each would otherwise wait its whole read_deadline, 0.1 s in lockstep), a
  /// warning names it once, and the device is dead until the plug-in answers again.
  double hung_timeout = 1.0;
  /// isolated: s without a wrench from Torsion after which the host fades the wrench it writes
  /// to the plug-in to zero by itself (wrench_watchdog.h): Torsion stopped or hung. 0: only when
  /// Torsion ends (lockstep runs serve the device on the simulated clock, with pauses as long
  /// as a step). The host fades on Torsion's end in any case.
  double watchdog_timeout = 0.1;
  double watchdog_fade_time = 0.2;  ///< isolated: s the host's fade takes from the limit to zero
  /// N and N m: the output stays within these even when the device could do more (a scene may
  /// ask for less than the hardware's limits; never for more).
  double max_force = std::numeric_limits<double>::infinity();
  double max_torque = std::numeric_limits<double>::infinity();

  /// Empty when valid, else the message naming the field.
  std::string validate() const;
};

/// Faults seen, per kind (summary.json's `plugin` entry).
struct PluginStats {
  std::atomic<std::uint64_t> reads{0};     ///< readings used
  std::atomic<std::uint64_t> late{0};      ///< reads that missed read_deadline
  std::atomic<std::uint64_t> failed{0};    ///< read() or write() returned non-zero
  std::atomic<std::uint64_t> rejected{0};  ///< readings with non-finite values or |q| != 1
  std::atomic<std::uint64_t> held{0};      ///< ticks that reused the last good reading
  std::atomic<std::uint64_t> dead{0};      ///< ticks reported dead (no good reading in hold_time)
};

class PluginDevice : public HapticDevice {
 public:
  /// Loads the library (in the host when isolated), checks its ABI version and table, opens the
  /// device and reads its info. Errors: "<library>: <what is wrong>".
  static Loaded<std::unique_ptr<PluginDevice>> open(const PluginDeviceSettings& settings);
  ~PluginDevice() override;
  PluginDevice(const PluginDevice&) = delete;
  PluginDevice& operator=(const PluginDevice&) = delete;

  std::string name() const override { return name_; }
  DeviceLimits limits() const override { return limits_; }
  DeviceSample read(double time) override;
  void write(const Wrench& wrench) override;

  /// The rate the device's own servo loop expects (info().rate_hz).
  double rateHz() const { return rate_hz_; }
  const PluginStats& stats() const { return *stats_; }
  bool isolated() const { return settings_.isolated; }
  /// Empty while the host runs (or in process); once the host has ended during the run, how:
  /// "killed by signal 11 (SIGSEGV)", "exited with code 3".
  std::string hostExit() const;
  /// The host process's id (0 in process); it is reaped by the time the device is destroyed.
  int hostProcessId() const;

 private:
  PluginDevice() = default;

  PluginDeviceSettings settings_;
  std::string name_;
  DeviceLimits limits_;
  double rate_hz_ = 0;
  std::shared_ptr<PluginStats> stats_;
  std::unique_ptr<PluginTransport> transport_;
  DeviceSample last_good_;
  bool have_good_ = false;
};

}  // namespace torsion::device
