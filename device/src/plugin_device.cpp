#include "torsion/device/plugin_device.h"

#include <dlfcn.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <mutex>
#include <thread>

#include "torsion/device/plugin_abi.h"
#include "torsion/device/scripted_device.h"

namespace torsion::device {

// Everything the worker thread touches. Owned jointly by the device and the worker, so that a
// worker abandoned inside a plug-in call that never returns still finds it when it does.
struct PluginDevice::Shared {
  void* library = nullptr;
  const torsion_device_v1* table = nullptr;
  void* handle = nullptr;
  std::shared_ptr<PluginStats> stats;

  std::mutex mutex;
  std::condition_variable wake;      // the worker waits here for work
  std::condition_variable answered;  // the loop waits here for a reading
  bool read_pending = false;
  double read_time = 0;
  std::uint64_t read_request = 0;
  std::uint64_t answered_request = 0;
  torsion_device_state state{};
  int read_status = 0;
  bool write_pending = false;
  double wrench[6] = {};
  bool quit = false;
  bool exited = false;
  std::thread worker;
};

namespace {

using Clock = std::chrono::steady_clock;

// The worker: every call into the plug-in happens here, one at a time, the newest wrench
// written before each read; close() last, after the final (zero) wrench.
void serve(const std::shared_ptr<PluginDevice::Shared>& s) {
  std::unique_lock<std::mutex> lock(s->mutex);
  for (;;) {
    s->wake.wait(lock, [&] { return s->quit || s->read_pending || s->write_pending; });
    if (s->write_pending) {
      double wrench[6];
      std::memcpy(wrench, s->wrench, sizeof wrench);
      s->write_pending = false;
      lock.unlock();
      const int status = s->table->write(s->handle, wrench);
      if (status != 0) ++s->stats->failed;
      lock.lock();
    }
    if (s->read_pending) {
      const double time = s->read_time;
      const std::uint64_t request = s->read_request;
      s->read_pending = false;
      lock.unlock();
      torsion_device_state state{};
      const int status = s->table->read(s->handle, time, &state);
      lock.lock();
      s->state = state;
      s->read_status = status;
      s->answered_request = request;
      s->answered.notify_all();
    }
    if (s->quit && !s->read_pending && !s->write_pending) {
      lock.unlock();
      s->table->close(s->handle);
      lock.lock();
      s->exited = true;
      s->answered.notify_all();
      return;
    }
  }
}

// A reading is used only when the call succeeded, every number is finite and the quaternion
// is a unit one (to 1e-3; it is then normalised).
bool acceptReading(int status, const torsion_device_state& state, DeviceSample& out) {
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

template <class Function>
Function symbolAs(void* symbol) {
  Function f;  // memcpy: ISO C++ has no cast from an object pointer to a function pointer
  static_assert(sizeof f == sizeof symbol);
  std::memcpy(&f, &symbol, sizeof f);
  return f;
}

}  // namespace

std::string PluginDeviceSettings::validate() const {
  if (library.empty()) return "library: the path of the plug-in's shared library is empty";
  if (!(read_deadline > 0 && read_deadline <= 1)) return "read_deadline must be in (0, 1] s";
  if (!(hold_time >= 0 && hold_time <= 1)) return "hold_time must be in [0, 1] s";
  if (!(close_timeout > 0)) return "close_timeout must be positive (s)";
  if (!(max_force >= 0) || !(max_torque >= 0)) return "max_force and max_torque must be >= 0";
  return {};
}

Loaded<std::unique_ptr<PluginDevice>> PluginDevice::open(const PluginDeviceSettings& settings) {
  using Result = Loaded<std::unique_ptr<PluginDevice>>;
  const std::string& path = settings.library;
  if (std::string bad = settings.validate(); !bad.empty()) return Result::fail(path + ": " + bad);

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
  void* handle = table->open(settings.config.c_str(), error, sizeof error);
  error[sizeof error - 1] = '\0';
  if (handle == nullptr) {
    return unload("open('" + settings.config +
                  "') failed: " + (error[0] ? error : "(the plug-in gave no reason)"));
  }
  torsion_device_info info{};
  const int status = table->info(handle, &info);
  info.name[sizeof info.name - 1] = '\0';
  std::string fault;
  if (status != 0) {
    fault = "info() failed with " + std::to_string(status);
  } else if (!(std::isfinite(info.max_force) && info.max_force >= 0)) {
    fault = "info(): max_force must be a finite number >= 0 N";
  } else if (!(std::isfinite(info.max_torque) && info.max_torque >= 0)) {
    fault = "info(): max_torque must be a finite number >= 0 N m";
  } else if (!(std::isfinite(info.rate_hz) && info.rate_hz > 0)) {
    fault = "info(): rate_hz must be a positive number";
  }
  if (!fault.empty()) {
    table->close(handle);
    return unload(fault);
  }

  std::unique_ptr<PluginDevice> device(new PluginDevice());
  device->settings_ = settings;
  device->name_ =
      "plugin(" + std::filesystem::path(path).filename().string() + ": " + info.name + ")";
  device->limits_ = defaultDeviceLimits();
  device->limits_.max_force = std::min(info.max_force, settings.max_force);
  device->limits_.max_torque = std::min(info.max_torque, settings.max_torque);
  device->rate_hz_ = info.rate_hz;
  device->stats_ = std::make_shared<PluginStats>();
  auto shared = std::make_shared<Shared>();
  shared->library = library;
  shared->table = table;
  shared->handle = handle;
  shared->stats = device->stats_;
  shared->worker = std::thread([shared] { serve(shared); });
  device->shared_ = std::move(shared);
  return Result{std::move(device), {}};
}

PluginDevice::~PluginDevice() {
  if (!shared_) return;
  Shared& s = *shared_;
  std::unique_lock<std::mutex> lock(s.mutex);
  s.quit = true;
  s.wake.notify_all();
  const auto until = Clock::now() + std::chrono::duration<double>(settings_.close_timeout);
  const bool exited = s.answered.wait_until(lock, until, [&] { return s.exited; });
  lock.unlock();
  if (exited) {
    s.worker.join();
    dlclose(s.library);
  } else {
    // The plug-in is stuck in a call. Its thread keeps `shared_` alive; the library stays
    // loaded, since unloading code that is running would crash the process.
    std::cerr << "torsion: " << name_ << " did not return within " << settings_.close_timeout
              << " s; abandoning it\n";
    s.worker.detach();
  }
}

DeviceSample PluginDevice::read(double time) {
  Shared& s = *shared_;
  torsion_device_state state{};
  int status = 0;
  bool answered = false;
  {
    std::unique_lock<std::mutex> lock(s.mutex);
    const bool asked = s.answered_request == request_;
    if (asked) {  // the worker is free: ask for a new reading
      s.read_pending = true;
      s.read_time = time;
      s.read_request = ++request_;
      s.wake.notify_one();
    }  // else the previous read is still inside the plug-in: let it finish, but do not use it
    const auto until = Clock::now() + std::chrono::duration<double>(settings_.read_deadline);
    answered = s.answered.wait_until(lock, until, [&] { return s.answered_request == request_; });
    // An answer to an earlier tick's request describes the device as it was then: late.
    answered = answered && asked;
    if (answered) {
      state = s.state;
      status = s.read_status;
    }
  }
  DeviceSample sample;
  sample.time = time;
  if (!answered) {
    ++stats_->late;
  } else if (status != 0) {
    ++stats_->failed;
  } else if (!acceptReading(status, state, sample)) {
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
  Shared& s = *shared_;
  const double w[6] = {wrench.force.x,  wrench.force.y,  wrench.force.z,
                       wrench.torque.x, wrench.torque.y, wrench.torque.z};
  std::lock_guard<std::mutex> lock(s.mutex);
  std::memcpy(s.wrench, w, sizeof w);
  s.write_pending = true;
  s.wake.notify_one();
}

}  // namespace torsion::device
