#include "torsion/device/plugin_device.h"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>

#include "plugin_transport.h"
#include "torsion/device/scripted_device.h"

namespace torsion::device {

namespace {

// openPluginLibrary on a thread of its own, waited for at most `timeout` s: a plug-in whose
// open() never returns (hardware that does not answer, an SDK waiting on a licence server) must
// not hang Torsion. An abandoned opening keeps its own state; should open() return after all,
// the thread closes the device and unloads the library (no call into it runs then).
Loaded<PluginLibrary> openPluginLibraryWithin(const std::string& path, const std::string& config,
                                              double timeout) {
  struct Opening {
    std::mutex mutex;
    std::condition_variable done_cv;
    bool done = false;
    bool abandoned = false;
    Loaded<PluginLibrary> result;
  };
  auto opening = std::make_shared<Opening>();
  std::thread([opening, path, config] {
    Loaded<PluginLibrary> result = openPluginLibrary(path, config);
    std::lock_guard<std::mutex> lock(opening->mutex);
    if (opening->abandoned) {
      if (result) closePluginLibrary(*result.value);
      return;
    }
    opening->result = std::move(result);
    opening->done = true;
    opening->done_cv.notify_all();
  }).detach();
  std::unique_lock<std::mutex> lock(opening->mutex);
  if (!opening->done_cv.wait_for(lock, std::chrono::duration<double>(timeout),
                                 [&] { return opening->done; })) {
    opening->abandoned = true;
    std::ostringstream message;
    message << path << ": the plug-in's open() did not return within " << timeout
            << " s (start_timeout); it is abandoned";
    return Loaded<PluginLibrary>::fail(message.str());
  }
  return std::move(opening->result);
}

}  // namespace

std::string PluginDeviceSettings::validate() const {
  if (library.empty()) return "library: the path of the plug-in's shared library is empty";
  if (!(read_deadline > 0 && read_deadline <= 1)) return "read_deadline must be in (0, 1] s";
  if (!(hold_time >= 0 && hold_time <= 1)) return "hold_time must be in [0, 1] s";
  if (!(close_timeout > 0)) return "close_timeout must be positive (s)";
  if (!(max_force >= 0) || !(max_torque >= 0)) return "max_force and max_torque must be >= 0";
  if (isolated && host_program.empty())
    return "host_program: an isolated plug-in needs the path of torsion_device_host";
  if (!(start_timeout > 0)) return "start_timeout must be positive (s)";
  if (!(hung_timeout > 0)) return "hung_timeout must be positive (s)";
  if (!(watchdog_timeout >= 0 && watchdog_timeout <= 10))
    return "watchdog_timeout must be in [0, 10] s";
  if (!(watchdog_fade_time > 0 && watchdog_fade_time <= 10))
    return "watchdog_fade_time must be in (0, 10] s";
  return {};
}

Loaded<std::unique_ptr<PluginDevice>> PluginDevice::open(const PluginDeviceSettings& settings) {
  using Result = Loaded<std::unique_ptr<PluginDevice>>;
  const std::string& path = settings.library;
  if (std::string bad = settings.validate(); !bad.empty()) return Result::fail(path + ": " + bad);

  std::unique_ptr<PluginDevice> device(new PluginDevice());
  device->settings_ = settings;
  device->stats_ = std::make_shared<PluginStats>();
  torsion_device_info info{};
  PluginLibrary in_process;
  if (settings.isolated) {
    auto started = startHostTransport(settings, device->stats_, info);
    if (!started) return Result::fail(started.error);
    device->transport_ = std::move(*started.value);
    // Checked in the host already; again here, where the answer is trusted.
    if (std::string fault = checkPluginInfo(info); !fault.empty())
      return Result::fail(path + ": " + fault);
  } else {
    auto opened = openPluginLibraryWithin(path, settings.config, settings.start_timeout);
    if (!opened) return Result::fail(opened.error);
    in_process = *opened.value;
    info = in_process.info;
  }
  device->name_ =
      "plugin(" + std::filesystem::path(path).filename().string() + ": " + info.name + ")";
  if (!settings.isolated)
    device->transport_ = makeThreadTransport(in_process, settings, device->stats_, device->name_);
  device->limits_ = defaultDeviceLimits();
  device->limits_.max_force = std::min(info.max_force, settings.max_force);
  device->limits_.max_torque = std::min(info.max_torque, settings.max_torque);
  device->rate_hz_ = info.rate_hz;
  return Result{std::move(device), {}};
}

PluginDevice::~PluginDevice() = default;  // the transport closes the plug-in

std::string PluginDevice::hostExit() const {
  return transport_->exitReason();
}

int PluginDevice::hostProcessId() const {
  return transport_->processId();
}

DeviceSample PluginDevice::read(double time) {
  torsion_device_state state{};
  int status = 0;
  const PluginTransport::Answer answer =
      transport_->read(time, settings_.read_deadline, state, status);
  DeviceSample sample;
  sample.time = time;
  if (answer == PluginTransport::Answer::kLate) {
    ++stats_->late;
  } else if (answer == PluginTransport::Answer::kGone) {
    // The host has ended: nothing will come, held and then dead as below.
  } else if (status != 0) {
    ++stats_->failed;
  } else if (!acceptPluginReading(status, state, sample)) {
    ++stats_->rejected;
  } else {
    ++stats_->reads;
    last_good_ = sample;
    have_good_ = true;
    return sample;
  }
  if (have_good_ && last_good_.alive && time - last_good_.time <= settings_.hold_time) {
    ++stats_->held;
    // Keeps the time of its reading: the loop books the age of the pose it renders from.
    return last_good_;
  }
  ++stats_->dead;
  DeviceSample dead = have_good_ ? last_good_ : DeviceSample{};
  dead.time = time;
  dead.alive = false;
  return dead;
}

void PluginDevice::write(const Wrench& wrench) {
  const double w[6] = {wrench.force.x,  wrench.force.y,  wrench.force.z,
                       wrench.torque.x, wrench.torque.y, wrench.torque.z};
  transport_->write(w);
}

}  // namespace torsion::device
