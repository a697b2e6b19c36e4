#include "torsion/device/plugin_library.h"

#include <dlfcn.h>

#include <cmath>
#include <cstring>

namespace torsion::device {

namespace {

template <class Function>
Function symbolAs(void* symbol) {
  Function f;  // memcpy: ISO C++ has no cast from an object pointer to a function pointer
  static_assert(sizeof f == sizeof symbol);
  std::memcpy(&f, &symbol, sizeof f);
  return f;
}

}  // namespace

std::string checkPluginInfo(const torsion_device_info& info) {
  if (!(std::isfinite(info.max_force) && info.max_force >= 0))
    return "info(): max_force must be a finite number >= 0 N";
  if (!(std::isfinite(info.max_torque) && info.max_torque >= 0))
    return "info(): max_torque must be a finite number >= 0 N m";
  if (!(std::isfinite(info.rate_hz) && info.rate_hz > 0))
    return "info(): rate_hz must be a positive number";
  return {};
}

Loaded<PluginLibrary> openPluginLibrary(const std::string& path, const std::string& config) {
  using Result = Loaded<PluginLibrary>;
  void* library = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    const char* why = dlerror();
    return Result::fail(
        path + ": cannot load the device plug-in: " + (why ? why : "unknown dlopen error"));
  }
  auto unload = [&](const std::string& message) {
    dlclose(library);
    return Result::fail(path + ": " + message);
  };
  void* symbol = dlsym(library, TORSION_DEVICE_ENTRY_SYMBOL);
  if (symbol == nullptr) {
    return unload(std::string("no entry point '") + TORSION_DEVICE_ENTRY_SYMBOL +
                  "': not a Torsion device plug-in (device/include/torsion/device/plugin_abi.h)");
  }
  const torsion_device_v1* table = symbolAs<torsion_device_entry_fn>(symbol)();
  if (table == nullptr) return unload("the entry point returned no function table");
  if (table->abi_version != TORSION_DEVICE_ABI_VERSION) {
    return unload("device plug-in ABI version " + std::to_string(table->abi_version) +
                  ", this Torsion speaks version " + std::to_string(TORSION_DEVICE_ABI_VERSION) +
                  ": rebuild the plug-in against this Torsion's plugin_abi.h");
  }
  if (!table->open || !table->info || !table->read || !table->write || !table->close)
    return unload("the function table has a null entry (open, info, read, write, close)");

  char error[256] = {};
  void* handle = table->open(config.c_str(), error, sizeof error);
  error[sizeof error - 1] = '\0';
  if (handle == nullptr) {
    return unload("open('" + config +
                  "') failed: " + (error[0] ? error : "(the plug-in gave no reason)"));
  }
  PluginLibrary plugin;
  plugin.library = library;
  plugin.table = table;
  plugin.handle = handle;
  const int status = table->info(handle, &plugin.info);
  plugin.info.name[sizeof plugin.info.name - 1] = '\0';
  const std::string fault =
      status != 0 ? "info() failed with " + std::to_string(status) : checkPluginInfo(plugin.info);
  if (!fault.empty()) {
    table->close(handle);
    return unload(fault);
  }
  return Result{plugin, {}};
}

void closePluginLibrary(PluginLibrary& plugin) {
  if (plugin.table && plugin.handle) plugin.table->close(plugin.handle);
  if (plugin.library) dlclose(plugin.library);
  plugin = PluginLibrary{};
}

bool acceptPluginReading(int status, const torsion_device_state& state, DeviceSample& out) {
  if (status != 0) return false;
  for (double v : state.position)
    if (!std::isfinite(v)) return false;
  double q2 = 0;
  for (double v : state.orientation) {
    if (!std::isfinite(v)) return false;
    q2 += v * v;
  }
  const double q = std::sqrt(q2);
  if (!(std::abs(q - 1) <= 1e-3)) return false;
  out.pose.position = {state.position[0], state.position[1], state.position[2]};
  out.pose.orientation = {state.orientation[0] / q, state.orientation[1] / q,
                          state.orientation[2] / q, state.orientation[3] / q};
  out.buttons = state.buttons;
  out.alive = state.alive != 0;
  return true;
}

}  // namespace torsion::device
