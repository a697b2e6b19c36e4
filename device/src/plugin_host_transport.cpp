// A plug-in in a process of its own, torsion_device_host (device/host/device_host_main.cpp),
// reached through one shared-memory request/response slot (plugin_host_protocol.h). A plug-in
// that crashes ends only the host: the loop sees its reads stop, this side reaps the host, names
// the signal, and the device is dead from then on.
#include <fcntl.h>
#include <spawn.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <iostream>
#include <mutex>
#include <new>
#include <thread>
#include <vector>

#include "plugin_host_protocol.h"
#include "plugin_transport.h"

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX declares it nowhere

namespace torsion::device {

namespace {

using Clock = std::chrono::steady_clock;
using host::Channel;
using host::futexWait;
using host::futexWake;

// Longest single futex sleep while waiting: between two, the host's exit is looked for, so a
// host that died is noticed within this even when the caller's deadline is long.
constexpr double kWaitSlice = 0.005;

Clock::time_point after(double seconds) {
  return Clock::now() +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
}

double secondsUntil(Clock::time_point until) {
  return std::chrono::duration<double>(until - Clock::now()).count();
}

std::string describeExit(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* abbreviation = sigabbrev_np(sig);
    return "killed by signal " + std::to_string(sig) +
           (abbreviation ? " (SIG" + std::string(abbreviation) + ")" : std::string());
  }
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  return "ended with wait status " + std::to_string(status);
}

// The shared page, mapped and constructed here, inherited by the host as kHostChannelFd.
struct Mapping {
  int fd = -1;
  Channel* channel = nullptr;
  ~Mapping() {
    if (channel) munmap(channel, sizeof(Channel));
    if (fd >= 0) close(fd);
  }
};

class HostTransport final : public PluginTransport {
 public:
  HostTransport(std::unique_ptr<Mapping> mapping, pid_t pid, const PluginDeviceSettings& settings,
                std::shared_ptr<PluginStats> stats)
      : mapping_(std::move(mapping)),
        channel_(*mapping_->channel),
        pid_(pid),
        library_(settings.library),
        close_timeout_(settings.close_timeout),
        hung_timeout_(settings.hung_timeout),
        stats_(std::move(stats)) {}

  ~HostTransport() override {
    if (!reaped_) closeHost();
  }

  // Waits for the host's open (request 1), then either hands over or explains.
  std::string awaitOpen(double timeout, torsion_device_info& info) {
    request_ = 1;
    if (!waitForResponse(after(timeout))) {
      if (reaped_) return "the device host ended while opening the plug-in: " + ended_how_;
      return "the device host did not open the plug-in within " + std::to_string(timeout) + " s";
    }
    if (channel_.status != 0) {
      channel_.error[sizeof channel_.error - 1] = '\0';
      return channel_.error[0] ? channel_.error : "the device host could not open the plug-in";
    }
    info = channel_.info;
    info.name[sizeof info.name - 1] = '\0';
    running_ = true;
    return {};
  }

  Answer read(double time, double deadline, torsion_device_state& state, int& status) override {
    if (reaped_) return Answer::kGone;
    const bool asked = idle();
    if (asked) {
      channel_.op = host::Op::kRead;
      channel_.time = time;
      send();
      asked_at_ = Clock::now();
      hung_warned_ = false;
    } else if (isHung()) {
      // Still inside the plug-in since long before this tick: waiting for it again would cost
      // every tick its whole deadline (0.1 s in lockstep: a run 100 times slower).
      return reapIfEnded() ? Answer::kGone : Answer::kLate;
    }  // else the host is still inside an earlier call: let it finish, but do not use it
    const bool answered = waitForResponse(after(deadline));
    if (reaped_) return Answer::kGone;
    if (!answered || !asked) return Answer::kLate;
    state = channel_.state;
    status = channel_.status;
    return Answer::kAnswered;
  }

  void write(const double wrench[6]) override {
    std::copy(wrench, wrench + 6, wrench_);
    has_wrench_ = true;
  }

  std::string exitReason() const override {
    std::lock_guard<std::mutex> lock(exit_mutex_);
    return exit_reason_;
  }

  int processId() const override { return static_cast<int>(pid_); }

 private:
  bool idle() const { return channel_.response.load(std::memory_order_acquire) == request_; }

  // Only while idle: the request fields are Torsion's until `request` moves.
  void send() {
    channel_.has_wrench = has_wrench_ ? 1 : 0;
    if (has_wrench_) {
      std::copy(wrench_, wrench_ + 6, channel_.wrench);
      wrench_request_ = request_ + 1;
    }
    has_wrench_ = false;
    channel_.request.store(++request_, std::memory_order_release);
    futexWake(channel_.request);
  }

  // True when the host answered request_ before `until`; false on time-out or when it ended.
  bool waitForResponse(Clock::time_point until) {
    for (;;) {
      const std::uint32_t seen = channel_.response.load(std::memory_order_acquire);
      if (seen == request_) {
        if (wrench_request_ == request_) {
          wrench_request_ = 0;
          if (channel_.write_status != 0) ++stats_->failed;
        }
        return true;
      }
      const double left = secondsUntil(until);
      if (left <= 0 || reapIfEnded()) return false;
      futexWait(channel_.response, seen, std::min(left, kWaitSlice));
    }
  }

  // True once the outstanding call has been inside the plug-in for hung_timeout; warns once.
  bool isHung() {
    const double inside = std::chrono::duration<double>(Clock::now() - asked_at_).count();
    if (inside <= hung_timeout_) return false;
    if (!hung_warned_) {
      std::cerr << "torsion: warning: the plug-in " << library_
                << " has not returned from read() for " << hung_timeout_
                << " s; the device is dead until it does and its force fades to zero\n";
      hung_warned_ = true;
    }
    return true;
  }

  // Reaps the host if it has ended (no zombie), records why, warns once. True when it has.
  bool reapIfEnded() {
    if (reaped_) return true;
    int status = 0;
    const pid_t got = waitpid(pid_, &status, WNOHANG);
    if (got == 0) return false;
    reaped_ = true;
    const std::string reason =
        got == pid_ ? describeExit(status) : std::string("lost (waitpid: ") + strerror(errno) + ")";
    ended_how_ = reason;
    if (running_) {
      {
        std::lock_guard<std::mutex> lock(exit_mutex_);
        exit_reason_ = reason;
      }
      std::cerr << "torsion: warning: the device host of " << library_ << " " << reason
                << "; the device is dead from now on and its force fades to zero\n";
    }
    return true;
  }

  // Close request (with the last wrench, the loop's zero) when the host is free, then exit;
  // a host that does not end within close_timeout is killed. Reaped in every case.
  void closeHost() {
    running_ = false;  // from here on its exit is expected
    const Clock::time_point until = after(close_timeout_);
    if (waitForResponse(until)) {  // free (or became so)
      channel_.op = host::Op::kClose;
      send();
      waitForResponse(until);
    }
    while (!reaped_) {
      int status = 0;
      const pid_t got = waitpid(pid_, &status, WNOHANG);
      if (got != 0) break;
      if (secondsUntil(until) <= 0) {
        std::cerr << "torsion: the device host of " << library_ << " did not close within "
                  << close_timeout_ << " s; killing it\n";
        kill(pid_, SIGKILL);
        waitpid(pid_, &status, 0);
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    reaped_ = true;
  }

  std::unique_ptr<Mapping> mapping_;
  Channel& channel_;
  pid_t pid_;
  std::string library_;
  double close_timeout_;
  double hung_timeout_;
  Clock::time_point asked_at_ = Clock::now();
  bool hung_warned_ = false;
  std::shared_ptr<PluginStats> stats_;
  std::uint32_t request_ = 0;
  std::uint32_t wrench_request_ = 0;  // the request that carried a wrench, until answered
  double wrench_[6] = {};
  bool has_wrench_ = false;
  bool reaped_ = false;
  bool running_ = false;   // opened and not yet closing: an exit now is a failure, and warned of
  std::string ended_how_;  // how the host ended, once reaped
  mutable std::mutex exit_mutex_;  // exit_reason_ is read by stats() callers on any thread
  std::string exit_reason_;        // set when the host ended while running
};

}  // namespace

Loaded<std::unique_ptr<PluginTransport>> startHostTransport(const PluginDeviceSettings& settings,
                                                            std::shared_ptr<PluginStats> stats,
                                                            torsion_device_info& info) {
  using Result = Loaded<std::unique_ptr<PluginTransport>>;
  const std::string& path = settings.library;
  auto fail = [&](const std::string& what) {
    return Result::fail(path + ": " + what + ": " + strerror(errno));
  };
  auto mapping = std::make_unique<Mapping>();
  mapping->fd = memfd_create("torsion-device-host", MFD_CLOEXEC);
  if (mapping->fd < 0) return fail("cannot create the device host's shared memory");
  if (mapping->fd == host::kHostChannelFd) {  // dup2 onto itself would keep close-on-exec
    const int moved = fcntl(mapping->fd, F_DUPFD_CLOEXEC, host::kHostChannelFd + 1);
    close(mapping->fd);
    mapping->fd = moved;
    if (moved < 0) return fail("cannot move the device host's shared memory");
  }
  if (ftruncate(mapping->fd, sizeof(Channel)) != 0)
    return fail("cannot size the device host's shared memory");
  void* memory = mmap(nullptr, sizeof(Channel), PROT_READ | PROT_WRITE, MAP_SHARED, mapping->fd, 0);
  if (memory == MAP_FAILED) return fail("cannot map the device host's shared memory");
  mapping->channel = new (memory) Channel();
  mapping->channel->watchdog_timeout = settings.watchdog_timeout;
  mapping->channel->watchdog_fade_time = settings.watchdog_fade_time;
  mapping->channel->request.store(1, std::memory_order_relaxed);  // the open (protocol header)

  // posix_spawn, not fork: Torsion has threads. The host gets the page as fd 3, default signal
  // dispositions and an empty signal mask, whatever this thread had.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, mapping->fd, host::kHostChannelFd);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setsigdefault(&attributes, &all);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  std::string parent = std::to_string(getpid());
  std::vector<std::string> args = {settings.host_program, settings.library, settings.config,
                                   parent};
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (std::string& a : args)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int spawned =
      posix_spawn(&pid, settings.host_program.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) {
    errno = spawned;
    return fail("cannot start the device host '" + settings.host_program + "'");
  }
  close(mapping->fd);  // the host has its copy; the mapping stays
  mapping->fd = -1;

  auto transport =
      std::make_unique<HostTransport>(std::move(mapping), pid, settings, std::move(stats));
  if (std::string error = transport->awaitOpen(settings.start_timeout, info); !error.empty()) {
    transport.reset();  // closes, else kills, and reaps the host
    // The host's own report already names the library; ours do not.
    return Result::fail(error.rfind(path + ":", 0) == 0 ? error : path + ": " + error);
  }
  return Result{std::unique_ptr<PluginTransport>(std::move(transport)), {}};
}

}  // namespace torsion::device
