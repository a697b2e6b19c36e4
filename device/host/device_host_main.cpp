// torsion_device_host LIBRARY CONFIG PARENT_PID: runs one device plug-in for Torsion, in a process
// of its own so that a plug-in that crashes ends this process, not Torsion's
// (docs/haptics.md, "Device plug-ins"). Started by PluginDevice (isolated), never by hand: it
// serves the shared-memory slot it inherits as fd 3 (plugin_host_protocol.h) until Torsion asks
// it to close or Torsion ends.
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "plugin_host_protocol.h"
#include "torsion/device/plugin_library.h"

// Under the sanitizers, let a plug-in's crash end this process with its own signal, which Torsion
// reports, rather than with the sanitizer's report and exit code.
extern "C" const char* __asan_default_options() {  // NOLINT(bugprone-reserved-identifier)
  return "handle_segv=0:handle_sigbus=0:handle_abort=0:handle_sigfpe=0:handle_sigill=0";
}
extern "C" const char* __tsan_default_options() {  // NOLINT(bugprone-reserved-identifier)
  return "handle_segv=0:handle_sigbus=0:handle_abort=0:handle_sigfpe=0:handle_sigill=0";
}

namespace {

using torsion::device::host::Channel;

void respond(Channel& channel, std::uint32_t request) {
  channel.response.store(request, std::memory_order_release);
  torsion::device::host::futexWake(channel.response);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr,
                 "usage: torsion_device_host LIBRARY CONFIG PARENT_PID (started by torsion)\n");
    return 2;
  }
  // Die with Torsion. The signal comes when the thread that started us ends, so the parent's pid
  // is also checked while idle: it changes only when the whole process has gone.
  const pid_t parent = static_cast<pid_t>(std::atol(argv[3]));
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) return 3;
  // Ctrl-C in a terminal reaches the whole process group; Torsion closes us itself when it stops.
  signal(SIGINT, SIG_IGN);

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

  std::uint32_t served = 1;
  for (;;) {
    const std::uint32_t request = channel.request.load(std::memory_order_acquire);
    if (request == served) {
      torsion::device::host::futexWait(channel.request, served, 1.0);
      if (getppid() != parent) return 3;
      continue;
    }
    served = request;
    if (channel.has_wrench != 0)
      channel.write_status = plugin.table->write(plugin.handle, channel.wrench);
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
