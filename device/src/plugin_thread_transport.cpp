// A plug-in in Torsion's process, every call made on a worker thread of its own so that a read()
// that blocks costs the loop no more than its deadline. A crash in the plug-in is a crash of the
// process: isolation is plugin_host_transport.cpp's job.
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <iostream>
#include <mutex>
#include <thread>

#include "plugin_transport.h"

namespace torsion::device {

namespace {

using Clock = std::chrono::steady_clock;

// Everything the worker thread touches. Owned jointly by the transport and the worker, so that a
// worker abandoned inside a plug-in call that never returns still finds it when it does.
struct Shared {
  PluginLibrary plugin;
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

// The worker: every call into the plug-in happens here, one at a time, the newest wrench
// written before each read; close() last, after the final (zero) wrench.
void serve(const std::shared_ptr<Shared>& s) {
  const torsion_device_v1& table = *s->plugin.table;
  void* handle = s->plugin.handle;
  std::unique_lock<std::mutex> lock(s->mutex);
  for (;;) {
    s->wake.wait(lock, [&] { return s->quit || s->read_pending || s->write_pending; });
    if (s->write_pending) {
      double wrench[6];
      std::memcpy(wrench, s->wrench, sizeof wrench);
      s->write_pending = false;
      lock.unlock();
      const int status = table.write(handle, wrench);
      if (status != 0) ++s->stats->failed;
      lock.lock();
    }
    if (s->read_pending) {
      const double time = s->read_time;
      const std::uint64_t request = s->read_request;
      s->read_pending = false;
      lock.unlock();
      torsion_device_state state{};
      const int status = table.read(handle, time, &state);
      lock.lock();
      s->state = state;
      s->read_status = status;
      s->answered_request = request;
      s->answered.notify_all();
    }
    if (s->quit && !s->read_pending && !s->write_pending) {
      lock.unlock();
      table.close(handle);
      lock.lock();
      s->exited = true;
      s->answered.notify_all();
      return;
    }
  }
}

class ThreadTransport final : public PluginTransport {
 public:
  ThreadTransport(PluginLibrary plugin, const PluginDeviceSettings& settings,
                  std::shared_ptr<PluginStats> stats, std::string name)
      : close_timeout_(settings.close_timeout),
        hung_timeout_(settings.hung_timeout),
        name_(std::move(name)) {
    shared_ = std::make_shared<Shared>();
    shared_->plugin = plugin;
    shared_->stats = std::move(stats);
    std::shared_ptr<Shared> shared = shared_;
    shared_->worker = std::thread([shared] { serve(shared); });
  }

  ~ThreadTransport() override {
    Shared& s = *shared_;
    std::unique_lock<std::mutex> lock(s.mutex);
    s.quit = true;
    s.wake.notify_all();
    const auto until = Clock::now() + std::chrono::duration<double>(close_timeout_);
    const bool exited = s.answered.wait_until(lock, until, [&] { return s.exited; });
    lock.unlock();
    if (exited) {
      s.worker.join();
      s.plugin.handle = nullptr;  // closed by the worker
      closePluginLibrary(s.plugin);
    } else {
      // The plug-in is stuck in a call. Its thread keeps `shared_` alive; the library stays
      // loaded, since unloading code that is running would crash the process.
      std::cerr << "torsion: " << name_ << " did not return within " << close_timeout_
                << " s; abandoning it\n";
      s.worker.detach();
    }
  }

  Answer read(double time, double deadline, torsion_device_state& state, int& status) override {
    Shared& s = *shared_;
    std::unique_lock<std::mutex> lock(s.mutex);
    const bool asked = s.answered_request == request_;
    if (asked) {  // the worker is free: ask for a new reading
      s.read_pending = true;
      s.read_time = time;
      s.read_request = ++request_;
      s.wake.notify_one();
      asked_at_ = Clock::now();
      hung_warned_ = false;
    } else if (isHung()) {
      // Still inside the plug-in since long before this tick: waiting for it again would cost
      // every tick its whole deadline (0.1 s in lockstep: a run 100 times slower).
      return Answer::kLate;
    }  // else the previous read is still inside the plug-in: let it finish, but do not use it
    const auto until = Clock::now() + std::chrono::duration<double>(deadline);
    const bool answered =
        s.answered.wait_until(lock, until, [&] { return s.answered_request == request_; });
    // An answer to an earlier tick's request describes the device as it was then: late.
    if (!answered || !asked) return Answer::kLate;
    state = s.state;
    status = s.read_status;
    return Answer::kAnswered;
  }

  void write(const double wrench[6]) override {
    Shared& s = *shared_;
    std::lock_guard<std::mutex> lock(s.mutex);
    std::memcpy(s.wrench, wrench, sizeof s.wrench);
    s.write_pending = true;
    s.wake.notify_one();
  }

 private:
  // True once the outstanding read() has been inside the plug-in for hung_timeout; warns once.
  bool isHung() {
    const double inside = std::chrono::duration<double>(Clock::now() - asked_at_).count();
    if (inside <= hung_timeout_) return false;
    if (!hung_warned_) {
      std::cerr << "torsion: warning: " << name_ << ": read() has not returned for "
                << hung_timeout_
                << " s; the device is dead until it does and its force fades to zero\n";
      hung_warned_ = true;
    }
    return true;
  }

  double close_timeout_;
  double hung_timeout_;
  Clock::time_point asked_at_ = Clock::now();
  bool hung_warned_ = false;
  std::string name_;
  std::shared_ptr<Shared> shared_;
  std::uint64_t request_ = 0;
};

}  // namespace

std::unique_ptr<PluginTransport> makeThreadTransport(PluginLibrary plugin,
                                                     const PluginDeviceSettings& settings,
                                                     std::shared_ptr<PluginStats> stats,
                                                     const std::string& name) {
  return std::make_unique<ThreadTransport>(plugin, settings, std::move(stats), name);
}

}  // namespace torsion::device
