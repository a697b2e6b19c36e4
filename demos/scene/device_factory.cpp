#include "device_factory.h"

#include <filesystem>

#include "data_directory.h"
#include "torsion/device/manual_device.h"
#include "torsion/device/network_device.h"
#include "torsion/device/plugin_device.h"
#include "torsion/device/scripted_device.h"
#include "torsion/device/spacemouse_device.h"
#include "torsion/device/udp_socket.h"

namespace torsion::scene {

namespace {

device::DeviceLimits limitsOf(const DeviceSpec& spec) {
  device::DeviceLimits limits = device::defaultDeviceLimits();
  limits.max_force = spec.max_force;
  limits.max_torque = spec.max_torque;
  return limits;
}

std::unique_ptr<device::HapticDevice> scripted(device::Trajectory trajectory,
                                               const DeviceSpec& spec) {
  const std::string name = std::string(toString(spec.kind)) + "(" +
                           std::filesystem::path(spec.file).filename().string() + ")";
  return std::make_unique<device::ScriptedDevice>(trajectory.playedAt(spec.speed), limitsOf(spec),
                                                  name);
}

// A plug-in that is not where it was named (a bare file name, or one the scene's directory does
// not hold) is looked for among the plug-ins installed with Torsion, <libdir>/torsion/plugins,
// found from the data directory (data_directory.h); otherwise the name is left to dlopen.
std::string pluginPath(const std::string& named) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(named, ec)) return named;
  const std::optional<std::string> data = dataDirectory();
  if (!data) return named;
  const fs::path installed =
      fs::path(*data) / TORSION_PLUGINS_FROM_DATA / fs::path(named).filename();
  return fs::is_regular_file(installed, ec) ? installed.lexically_normal().string() : named;
}

// The device host that runs an isolated plug-in, installed (and built) in <libdir>/torsion, found
// from the data directory like the plug-ins; empty when it is not there.
std::string deviceHostProgram() {
  namespace fs = std::filesystem;
  std::error_code ec;
  const std::optional<std::string> data = dataDirectory();
  if (!data) return {};
  const fs::path host = fs::path(*data) / TORSION_DEVICE_HOST_FROM_DATA;
  return fs::is_regular_file(host, ec) ? host.lexically_normal().string() : std::string();
}

}  // namespace

Result<std::unique_ptr<device::HapticDevice>> openDevice(const DeviceSpec& spec, bool lockstep) {
  switch (spec.kind) {
    case DeviceSpec::Kind::kScripted: {
      device::Loaded<device::Trajectory> t = device::loadTrajectory(spec.file);
      if (!t) return Error{t.error};
      return scripted(std::move(*t.value), spec);
    }
    case DeviceSpec::Kind::kReplay: {
      device::Loaded<device::Trajectory> t = device::loadRecordedTrajectory(spec.file);
      if (!t) return Error{t.error};
      return scripted(std::move(*t.value), spec);
    }
    case DeviceSpec::Kind::kNetwork: {
      device::NetworkDeviceSettings settings;
      if (!device::parseIpv4(spec.host, settings.local.address))
        return Error{"'" + spec.host + "' is not an IPv4 address"};
      settings.local.port = static_cast<std::uint16_t>(spec.port);
      settings.timeout = spec.timeout;
      settings.limits = limitsOf(spec);
      if (!spec.key_file.empty()) {
        device::Loaded<device::PacketKey> key = device::PacketKey::fromFile(spec.key_file);
        if (!key) return Error{key.error};
        settings.key = std::move(*key.value);
      } else {
        device::Loaded<std::optional<device::PacketKey>> key = device::PacketKey::fromEnvironment();
        if (!key) return Error{key.error};
        settings.key = std::move(*key.value);
      }
      auto opened = device::NetworkDevice::open(settings);
      if (!opened) return Error{opened.error};
      return std::unique_ptr<device::HapticDevice>(std::move(*opened.value));
    }
    case DeviceSpec::Kind::kSpaceMouse: {
      auto opened = device::openSpaceMouse(spec.spacemouse);
      if (!opened) return Error{opened.error};
      return std::move(*opened.value);
    }
    case DeviceSpec::Kind::kPlugin: {
      device::PluginDeviceSettings settings;
      settings.library = pluginPath(spec.file);
      settings.config = spec.config;
      settings.max_force = spec.max_force;
      settings.max_torque = spec.max_torque;
      settings.isolated = spec.isolated;
      if (spec.isolated) {
        settings.host_program = deviceHostProgram();
        if (settings.host_program.empty()) {
          return Error{
              settings.library +
              ": the device host torsion_device_host, which runs an isolated plug-in, "
              "is not installed beside this torsion (<libdir>/torsion); run the plug-in "
              "in process instead (\"isolated\": false, or --device HAND=plugin-inproc:...)"};
        }
      }
      if (lockstep) {
        settings.read_deadline = 0.1;
        // The simulated clock pauses the loop for as long as a step takes: no wall-clock
        // watchdog (the host still fades when Torsion ends).
        settings.watchdog_timeout = 0;
      }
      auto opened = device::PluginDevice::open(settings);
      if (!opened) return Error{opened.error};
      return std::unique_ptr<device::HapticDevice>(std::move(*opened.value));
    }
    case DeviceSpec::Kind::kManual:  // the viewer sets its pose (SceneHaptics::manualTool)
      return std::unique_ptr<device::HapticDevice>(
          std::make_unique<device::ManualDevice>(limitsOf(spec)));
  }
  return Error{"unknown device kind"};
}

}  // namespace torsion::scene
