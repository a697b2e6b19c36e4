#pragma once
// How PluginDevice reaches its plug-in's calls: on a worker thread in Torsion's process
// (plugin_thread_transport.cpp) or in the device host process (plugin_host_transport.cpp). The
// device applies the same checks, hold and dead rules to what either returns (plugin_device.cpp).

#include <memory>
#include <string>

#include "torsion/device/plugin_abi.h"
#include "torsion/device/plugin_device.h"
#include "torsion/device/plugin_library.h"

namespace torsion::device {

class PluginTransport {
 public:
  enum class Answer {
    kAnswered,  ///< the plug-in answered this request in time: state and status are its answer
    kLate,      ///< no answer by the deadline (maybe still working on this or an older request)
    kGone,      ///< the plug-in will never answer again (its host process ended)
  };

  /// Sends the final wrench already written, closes the plug-in and releases it (thread joined
  /// or abandoned; host process closed, else killed, and reaped) within about close_timeout.
  virtual ~PluginTransport() = default;

  /// From the loop's thread: asks for a reading at `time` (the newest written wrench goes
  /// first) and waits for it at most `deadline` s.
  virtual Answer read(double time, double deadline, torsion_device_state& state, int& status) = 0;
  /// From the loop's thread: the wrench to hand the plug-in's write() before its next read().
  virtual void write(const double wrench[6]) = 0;
  /// Empty while the plug-in may still answer; else why it ended ("killed by signal 11 (SIGSEGV)").
  virtual std::string exitReason() const { return {}; }
  /// The host process's id, 0 in process.
  virtual int processId() const { return 0; }
};

/// The plug-in already opened in this process, served by a worker thread.
std::unique_ptr<PluginTransport> makeThreadTransport(PluginLibrary plugin,
                                                     const PluginDeviceSettings& settings,
                                                     std::shared_ptr<PluginStats> stats,
                                                     const std::string& name);

/// Starts settings.host_program on settings.library and settings.config and waits for it to open
/// the plug-in; `info` receives the plug-in's info (checked by the caller).
Loaded<std::unique_ptr<PluginTransport>> startHostTransport(const PluginDeviceSettings& settings,
                                                            std::shared_ptr<PluginStats> stats,
                                                            torsion_device_info& info);

}  // namespace torsion::device
