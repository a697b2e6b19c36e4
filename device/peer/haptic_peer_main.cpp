// torsion_haptic_peer: the reference peer of the network device. It stands where a vendor's
// force-feedback driver would: it sends the poses of a scripted trajectory to the simulation at
// a fixed rate over UDP and receives the wrenches to render (docs/haptic-devices.md,
// "Packet format").
//
//   torsion_haptic_peer --trajectory assets/trajectories/figure_6_7.json [--port 5750]
//                       [--rate 1000] [--log received.csv] [--key-file FILE]
//
// With --key-file (or TORSION_HAPTIC_KEY_FILE / TORSION_HAPTIC_KEY in the environment) it signs
// its packets with the shared key (packet_key.h); the key itself is never an argument. What it
// renders fades to zero when the simulation's wrenches stop arriving (wrench_watchdog.h).
#include <signal.h>  // NOLINT(modernize-deprecated-headers): POSIX sigaction
#include <time.h>    // NOLINT(modernize-deprecated-headers): POSIX clock_gettime and friends

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <fstream>
#include <optional>
#include <string>

#include "torsion/device/network_peer.h"
#include "torsion/device/packet_key.h"
#include "torsion/device/trajectory.h"

namespace {

// SIGINT/SIGTERM end the loop; the peer then says goodbye and closes its log whole.
volatile sig_atomic_t g_stop = 0;
void requestStop(int) {
  g_stop = 1;
}

double monotonicSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

namespace {

// The peer; main() below only turns an escaping exception (out of memory) into an error line.
// Its options, its session and its loop read in order as one program.
// NOLINTNEXTLINE(readability-function-size)
int runPeer(int argc, char** argv) {
  using namespace torsion::device;
  std::string trajectory_path, log_path, host = "127.0.0.1";
  int port = 5750;
  double rate = 1000;
  std::string key_path;
  CLI::App app{
      "torsion_haptic_peer: sends a scripted device trajectory to a simulation's network "
      "device over UDP and receives the wrenches (docs/haptic-devices.md)"};
  app.add_option("--trajectory", trajectory_path, "Trajectory file (JSON)")->required();
  app.add_option("--port", port, "The simulation's UDP port")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  app.add_option("--host", host, "The simulation's IPv4 address")->capture_default_str();
  app.add_option("--rate", rate, "Poses sent per second (Hz)")
      ->check(CLI::Range(1e-3, 1e6))
      ->capture_default_str();
  app.add_option("--log", log_path,
                 "Write the wrench rendered each tick to this CSV file (the one received; faded "
                 "to zero when wrenches stop arriving)");
  app.add_option("--key-file", key_path,
                 "Shared key file: sign packets (docs/haptic-devices.md, \"Authentication\"); also "
                 "TORSION_HAPTIC_KEY_FILE or TORSION_HAPTIC_KEY in the environment");
  for (int k = 1; k < argc; ++k) {  // refused before parsing: never echoed, never used
    const std::string a = argv[k];
    if (a == "--key" || a.rfind("--key=", 0) == 0) {
      std::fprintf(stderr,
                   "error: --key: a key on the command line is visible to every local user; put "
                   "it in a file (--key-file) or in TORSION_HAPTIC_KEY\n");
      return 1;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return e.get_exit_code() == 0 ? app.exit(e) : (app.exit(e), 2);  // usage errors: exit 2
  }
  std::optional<PacketKey> key;
  if (!key_path.empty()) {
    Loaded<PacketKey> loaded = PacketKey::fromFile(key_path);
    if (!loaded) {
      std::fprintf(stderr, "error: %s\n", loaded.error.c_str());
      return 1;
    }
    key = std::move(*loaded.value);
  } else {
    Loaded<std::optional<PacketKey>> loaded = PacketKey::fromEnvironment();
    if (!loaded) {
      std::fprintf(stderr, "error: %s\n", loaded.error.c_str());
      return 1;
    }
    key = std::move(*loaded.value);
  }
  UdpEndpoint simulation;
  simulation.port = static_cast<std::uint16_t>(port);
  if (!parseIpv4(host, simulation.address)) {
    std::fprintf(stderr, "error: --host %s is not an IPv4 address\n", host.c_str());
    return 1;
  }
  Loaded<Trajectory> trajectory = loadTrajectory(trajectory_path);
  if (!trajectory) {
    std::fprintf(stderr, "error: %s\n", trajectory.error.c_str());
    return 1;
  }
  const bool signing = key.has_value();
  auto peer = NetworkPeer::open(simulation, *trajectory.value, std::move(key));
  if (!peer) {
    std::fprintf(stderr, "error: %s\n", peer.error.c_str());
    return 1;
  }
  std::ofstream log;
  if (!log_path.empty()) {
    log.open(log_path);
    log << "time,fx,fy,fz,tx,ty,tz,echo_sequence\n";
  }
  NetworkPeer& p = **peer.value;
  const double period = 1 / rate;
  const double duration = p.trajectory().duration() + 0.5;  // hold the end a little
  std::fprintf(stderr, "peer: sending %s to %s:%d at %g Hz for %.1f s, %s\n",
               trajectory_path.c_str(), host.c_str(), port, rate, duration,
               signing ? "signed with the shared key" : "unauthenticated");
  struct sigaction action {};
  action.sa_handler = requestStop;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  const double origin = monotonicSeconds();
  for (long k = 0; !g_stop; ++k) {
    const double deadline = origin + static_cast<double>(k) * period;
    timespec ts{static_cast<time_t>(deadline), static_cast<long>(std::fmod(deadline, 1.0) * 1e9)};
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    const double t = monotonicSeconds() - origin;
    if (t > duration) break;
    p.tick(t);
    if (log.is_open()) {
      const Wrench& w = p.renderedWrench();  // what the device renders (watchdog: fades)
      log << t << ',' << w.force.x << ',' << w.force.y << ',' << w.force.z << ',' << w.torque.x
          << ',' << w.torque.y << ',' << w.torque.z << ',' << p.newestEcho() << '\n';
    }
  }
  p.sayGoodbye(monotonicSeconds() - origin);  // frees the simulation's device for another peer
  const PacketStats& s = p.stats();
  std::fprintf(stderr,
               "peer: sent %llu poses, accepted %llu wrenches, rejected %llu (unauthenticated "
               "%llu, other session %llu, older packet version %llu)\n",
               static_cast<unsigned long long>(s.sent.load()),
               static_cast<unsigned long long>(s.accepted.load()),
               static_cast<unsigned long long>(s.rejected()),
               static_cast<unsigned long long>(s.unauthenticated.load()),
               static_cast<unsigned long long>(s.replayed.load()),
               static_cast<unsigned long long>(s.old_version.load()));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return runPeer(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
