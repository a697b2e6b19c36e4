// torsion_device_host LIBRARY CONFIG PARENT_PID: runs one device plug-in for Torsion, in a process
// of its own so that a plug-in that crashes ends this process, not Torsion's
// (docs/haptic-devices.md, "Device plug-ins"). Started by PluginDevice (isolated), never by hand:
// it serves the shared-memory slot it inherits as fd 3 (plugin_host_protocol.h) until Torsion asks
// it to close or Torsion ends. When Torsion's wrenches stop coming (Torsion stopped or hung) or
// Torsion ends, the host fades the device's wrench to zero itself (wrench_watchdog.h).
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <time.h>  // NOLINT(modernize-deprecated-headers): POSIX clock_gettime, nanosleep
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "plugin_host_protocol.h"
#include "torsion/device/plugin_library.h"
#include "torsion/device/wrench_watchdog.h"

// Under the sanitizers, let a plug-in's crash end this process with its own signal, which Torsion
// reports, rather than with the sanitizer's report and exit code.
extern "C" const char* __asan_default_options() {  // NOLINT(bugprone-reserved-identifier)
  return "handle_segv=0:handle_sigbus=0:handle_abort=0:handle_sigfpe=0:handle_sigill=0";
}
extern "C" const char* __tsan_default_options() {  // NOLINT(bugprone-reserved-identifier)
  return "handle_segv=0:handle_sigbus=0:handle_abort=0:handle_sigfpe=0:handle_sigill=0";
}

namespace {

using torsion::device::Wrench;
using torsion::device::WrenchWatchdog;
using torsion::device::host::Channel;

// s between the host's own checks and writes while it holds a non-zero wrench: the rate of
// Torsion's loop, so a fade is as smooth as the loop's own.
constexpr double kWatchTick = 0.001;
// s a plug-in's calls may take once Torsion has gone before the host ends anyway (SIGALRM).
constexpr unsigned kLastCallsLimit = 2;

// Torsion ended (PR_SET_PDEATHSIG) or the host was told to stop: the main loop fades the wrench
// out and closes the plug-in. The alarm ends the host even if a plug-in call never returns.
volatile sig_atomic_t g_torsion_gone = 0;
extern "C" void onTorsionGone(int) {
  g_torsion_gone = 1;
  alarm(kLastCallsLimit);
}

double monotonicSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

void respond(Channel& channel, std::uint32_t request) {
  channel.response.store(request, std::memory_order_release);
  torsion::device::host::futexWake(channel.response);
}

bool isZero(const Wrench& w) {
  return w.force.x == 0 && w.force.y == 0 && w.force.z == 0 && w.torque.x == 0 && w.torque.y == 0 &&
         w.torque.z == 0;
}

// What the plug-in is told to render, and the last wrench it was given.
class Output {
 public:
  explicit Output(torsion::device::PluginLibrary& plugin) : plugin_(plugin) {}
  std::int32_t write(const Wrench& w) {
    const double v[6] = {w.force.x, w.force.y, w.force.z, w.torque.x, w.torque.y, w.torque.z};
    last_ = w;
    return plugin_.table->write(plugin_.handle, v);
  }
  const Wrench& last() const { return last_; }

 private:
  torsion::device::PluginLibrary& plugin_;
  Wrench last_;
};

Wrench fromArray(const double v[6]) {
  return {{v[0], v[1], v[2]}, {v[3], v[4], v[5]}};
}

// Torsion is gone: the wrench fades to zero as on a stall, then the plug-in is closed.
int fadeOutAndClose(torsion::device::PluginLibrary& plugin, Output& output,
                    WrenchWatchdog& watchdog) {
  watchdog.lost(monotonicSeconds());
  while (!watchdog.faded()) {
    output.write(watchdog.render(monotonicSeconds()));
    const timespec tick{0, static_cast<long>(kWatchTick * 1e9)};
    nanosleep(&tick, nullptr);
  }
  torsion::device::closePluginLibrary(plugin);
  return 3;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr,
                 "usage: torsion_device_host LIBRARY CONFIG PARENT_PID (started by torsion)\n");
    return 2;
  }
  // Notice Torsion's end. The signal comes when the thread that started us ends, so the
  // parent's pid is also checked while idle: it changes only when the whole process has gone.
  // Either way the wrench fades out before the host ends (never a held wrench, never a step).
  struct sigaction gone {};
  gone.sa_handler = onTorsionGone;
  sigemptyset(&gone.sa_mask);
  sigaction(SIGTERM, &gone, nullptr);
  const pid_t parent = static_cast<pid_t>(std::atol(argv[3]));
  prctl(PR_SET_PDEATHSIG, SIGTERM);
  if (getppid() != parent) return 3;
  // Ctrl-C in a terminal, or the terminal closing, reaches the whole process group; Torsion
  // stops on them and closes us itself.
  signal(SIGINT, SIG_IGN);
  signal(SIGHUP, SIG_IGN);

  struct stat page {};
  if (fstat(torsion::device::host::kHostChannelFd, &page) != 0 ||
      page.st_size < static_cast<off_t>(sizeof(Channel))) {
    std::fprintf(stderr, "torsion_device_host: no channel on fd 3 (started by torsion only)\n");
    return 2;
  }
  void* memory = mmap(nullptr, sizeof(Channel), PROT_READ | PROT_WRITE, MAP_SHARED,
                      torsion::device::host::kHostChannelFd, 0);
  if (memory == MAP_FAILED) return 2;
  Channel& channel = *static_cast<Channel*>(memory);  // constructed by Torsion

  auto opened = torsion::device::openPluginLibrary(argv[1], argv[2]);
  if (!opened) {
    std::snprintf(channel.error, sizeof channel.error, "%s", opened.error.c_str());
    channel.status = -1;
    respond(channel, 1);
    return 1;
  }
  torsion::device::PluginLibrary plugin = *opened.value;
  channel.info = plugin.info;
  channel.status = 0;
  respond(channel, 1);

  // Between Torsion's wrenches and the plug-in: when they stop coming (Torsion stopped, hung or
  // gone), the host fades what the device renders to zero by itself (wrench_watchdog.h).
  torsion::device::DeviceLimits limits;
  limits.max_force = plugin.info.max_force;
  limits.max_torque = plugin.info.max_torque;
  WrenchWatchdog watchdog({channel.watchdog_timeout, channel.watchdog_fade_time}, limits);
  Output output(plugin);

  std::uint32_t served = 1;
  for (;;) {
    if (g_torsion_gone != 0 || getppid() != parent)
      return fadeOutAndClose(plugin, output, watchdog);
    const std::uint32_t request = channel.request.load(std::memory_order_acquire);
    if (request == served) {
      const double now = monotonicSeconds();
      if (watchdog.fading(now) && !isZero(output.last())) output.write(watchdog.render(now));
      // While a wrench is held, wake at the loop's rate to notice its sender stopping.
      torsion::device::host::futexWait(channel.request, served,
                                       isZero(output.last()) ? 1.0 : kWatchTick);
      continue;
    }
    served = request;
    if (channel.has_wrench != 0) {
      const double now = monotonicSeconds();
      watchdog.receive(fromArray(channel.wrench), now);
      channel.write_status = output.write(watchdog.render(now));
    }
    if (channel.op == torsion::device::host::Op::kClose) {
      torsion::device::closePluginLibrary(plugin);
      respond(channel, served);
      return 0;
    }
    torsion_device_state state{};
    channel.status = plugin.table->read(plugin.handle, channel.time, &state);
    channel.state = state;
    respond(channel, served);
  }
}
