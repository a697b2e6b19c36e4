#pragma once
// One device plug-in library opened and checked (plugin_abi.h): the checks every way of running a
// plug-in shares, in Torsion's process (PluginDevice in-process) or in the device host
// (torsion_device_host, PluginDevice isolated).
//
//   - the entry symbol must exist and its table must carry TORSION_DEVICE_ABI_VERSION;
//   - every function pointer must be set;
//   - open(config) must return a handle; info() must succeed and give finite non-negative limits
//     and a positive rate (checkPluginInfo).
// Errors: "<library>: <what is wrong>". On any error nothing stays open or loaded.

#include <string>

#include "torsion/device/device_types.h"
#include "torsion/device/loaded.h"
#include "torsion/device/plugin_abi.h"

namespace torsion::device {

struct PluginLibrary {
  void* library = nullptr;                   ///< dlopen handle
  const torsion_device_v1* table = nullptr;  ///< the plug-in's function table
  void* handle = nullptr;                    ///< what the plug-in's open() returned
  torsion_device_info info{};                ///< checked, name NUL-terminated
};

/// dlopen + ABI checks + open(config) + info(), as above.
Loaded<PluginLibrary> openPluginLibrary(const std::string& path, const std::string& config);

/// Calls the plug-in's close() and unloads the library. Only when no call into it is running.
void closePluginLibrary(PluginLibrary& plugin);

/// Empty when `info` is usable (finite limits >= 0, rate > 0), else what is wrong with it.
std::string checkPluginInfo(const torsion_device_info& info);

/// A reading is used only when the call succeeded (status 0), every number is finite and the
/// quaternion is a unit one to 1e-3 (it is then normalised into `out`).
bool acceptPluginReading(int status, const torsion_device_state& state, DeviceSample& out);

}  // namespace torsion::device
