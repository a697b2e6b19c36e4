#pragma once
// A haptic device in a shared library, loaded at run time through the C ABI of plugin_abi.h
// (`--device HAND=plugin:/path/libdev.so[:CONFIG]`, docs/haptics.md).
//
// The loader trusts nothing the library returns:
//   - open: the entry symbol must exist and its table must carry TORSION_DEVICE_ABI_VERSION,
//     every function pointer must be set, info() must give finite non-negative limits and a
//     positive rate; otherwise open() fails with a message naming the library and the fault;
//   - every tick: the plug-in is called on a worker thread of its own, and read() waits for it
//     only until `read_deadline` (an answer that comes later, to an earlier tick, is not used); a
//     reading that is late, failed (non-zero return), non-finite or has a non-unit quaternion is
//     not used: the device keeps its last good reading for at most `hold_time` (a late tick on a
//     busy machine does not fade the force), then reports itself dead, so the haptic loop's safety
//     filter fades the output to zero exactly as for a built-in device that stopped answering. Each
//     kind of fault is counted (stats()).
//   - a plug-in that never returns is abandoned at destruction after `close_timeout`: its
//     thread is detached and the library stays loaded (unloading code that may still run would
//     crash), and the run goes on.
//
// Threads: read(), write() from the haptic loop's thread only (as every HapticDevice); stats()
// from any thread. The plug-in itself is only ever called from the worker thread, one call at a
// time.

#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>

#include "torsion/device/haptic_device.h"
#include "torsion/device/loaded.h"

namespace torsion::device {

struct PluginDeviceSettings {
  std::string library;            ///< path of the shared library (dlopen)
  std::string config;             ///< text handed to the plug-in's open(), maybe empty
  double read_deadline = 0.0005;  ///< s the loop waits for one read() of the plug-in
  double hold_time = 0.005;       ///< s a good reading may stand in for late or bad ones
  double close_timeout = 1.0;     ///< s to wait for the plug-in's last calls at destruction
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
  /// Loads the library, checks its ABI version and table, opens the device and reads its
  /// info. Errors: "<library>: <what is wrong>".
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

  struct Shared;  // state shared with the worker thread (plugin_device.cpp)

 private:
  PluginDevice() = default;

  PluginDeviceSettings settings_;
  std::string name_;
  DeviceLimits limits_;
  double rate_hz_ = 0;
  std::shared_ptr<Shared> shared_;
  std::shared_ptr<PluginStats> stats_;
  DeviceSample last_good_;
  bool have_good_ = false;
  std::uint64_t request_ = 0;
};

}  // namespace torsion::device
