// The example device plug-in (device/include/torsion/device/plugin_abi.h): a simulated
// force-feedback arm held by a simulated operator (simulated_arm.h). Load it with
//   torsion run scene.json --device hand=plugin:build/device/plugins/simulated_device/
//       libtorsion_simulated_device.so:intent=twist,intent_rate=0.5,delay=0.02
// A vendor SDK's plug-in has the same shape: open() connects to the hardware, read() asks the
// SDK for the pose and buttons, write() hands it the wrench, close() zeroes and disconnects.

#include <cstdio>
#include <cstring>
#include <new>

#include "simulated_arm.h"
#include "torsion/device/plugin_abi.h"

namespace {

using torsion::simulated::ArmState;
using torsion::simulated::SimulatedArm;
using torsion::simulated::SimulatedArmSettings;

void* openDevice(const char* config, char* error, size_t error_size) {
  SimulatedArmSettings settings;
  const std::string fault = settings.parse(config ? config : "");
  if (!fault.empty()) {
    std::snprintf(error, error_size, "simulated device: %s", fault.c_str());
    return nullptr;
  }
  return new (std::nothrow) SimulatedArm(settings);
}

int info(void* handle, torsion_device_info* out) {
  const SimulatedArmSettings& s = static_cast<SimulatedArm*>(handle)->settings();
  out->max_force = s.max_force;
  out->max_torque = s.max_torque;
  out->rate_hz = 1000;
  std::snprintf(out->name, sizeof out->name, "simulated %.2g kg, %.3g Hz motors, %.3g ms delay",
                s.device_mass, s.motor_bandwidth_hz, 1e3 * s.delay);
  return 0;
}

int read(void* handle, double time, torsion_device_state* out) {
  const ArmState state = static_cast<SimulatedArm*>(handle)->read(time);
  std::memcpy(out->position, state.position, sizeof out->position);
  std::memcpy(out->orientation, state.orientation, sizeof out->orientation);
  out->buttons = state.buttons;
  out->alive = 1;
  return 0;
}

int write(void* handle, const double wrench[6]) {
  static_cast<SimulatedArm*>(handle)->write(wrench);
  return 0;
}

void closeDevice(void* handle) {
  delete static_cast<SimulatedArm*>(handle);
}

const torsion_device_v1 kTable = {
    TORSION_DEVICE_ABI_VERSION, 0, openDevice, info, read, write, closeDevice};

}  // namespace

extern "C" __attribute__((visibility("default"))) const torsion_device_v1* torsion_device_plugin(
    void) {
  return &kTable;
}
