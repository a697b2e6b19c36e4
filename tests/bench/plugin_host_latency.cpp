// Round-trip latency of one PluginDevice::read() of the example plug-in, isolated in the device
// host (shared memory, futex wake-ups both ways) and in process (worker thread, condition
// variables), paced at the loop's 1 kHz so that each read wakes a sleeping server, as in a run.
// Not a test: it measures (docs/haptic-devices.md, "Isolated or in process").
//
//   bench_plugin_host_latency [READS]   (default 5000 per mode)
//
// Prints p50/p99/max in microseconds per mode, the late reads (past the default 0.5 ms deadline),
// and the 1-minute load average: wall-clock figures on a shared machine move with its load.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include "torsion/device/plugin_device.h"

namespace {

using Clock = std::chrono::steady_clock;

void measure(bool isolated, int reads) {
  torsion::device::PluginDeviceSettings settings;
  settings.library = TORSION_SIMULATED_DEVICE_PLUGIN;
  settings.host_program = TORSION_DEVICE_HOST;
  settings.isolated = isolated;
  auto opened = torsion::device::PluginDevice::open(settings);
  if (!opened) {
    std::fprintf(stderr, "%s\n", opened.error.c_str());
    std::exit(1);
  }
  torsion::device::PluginDevice& device = **opened.value;
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(reads));
  auto next = Clock::now();
  for (int k = 0; k < reads; ++k) {
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
    const auto start = Clock::now();
    device.read(k * 0.001);
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - start).count());
    device.write(torsion::device::Wrench{});
  }
  std::sort(us.begin(), us.end());
  auto at = [&](double q) {
    return us[static_cast<std::size_t>(q * static_cast<double>(us.size() - 1))];
  };
  std::printf("%-10s reads %d  p50 %.1f us  p99 %.1f us  max %.1f us  late %llu\n",
              isolated ? "isolated" : "in-process", reads, at(0.5), at(0.99), us.back(),
              static_cast<unsigned long long>(device.stats().late.load()));
}

}  // namespace

int main(int argc, char** argv) {
  const int reads = argc > 1 ? std::atoi(argv[1]) : 5000;
  if (reads < 1) return 2;
  measure(true, reads);
  measure(false, reads);
  double load[1] = {0};
  if (getloadavg(load, 1) == 1) std::printf("load average (1 min) %.2f\n", load[0]);
  return 0;
}
