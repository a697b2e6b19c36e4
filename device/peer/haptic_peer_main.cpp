// torsion_haptic_peer: the reference peer of the network device. It stands where a vendor's
// force-feedback driver would: it sends the poses of a scripted trajectory to the simulation at
// a fixed rate over UDP and receives the wrenches to render (docs/haptics.md, "Packet format").
//
//   torsion_haptic_peer --trajectory assets/trajectories/figure_6_7.json [--port 5750]
//                       [--rate 1000] [--log received.csv] [--key-file FILE]
//
// With --key-file (or TORSION_HAPTIC_KEY_FILE / TORSION_HAPTIC_KEY in the environment) it signs
// its packets with the shared key (packet_key.h); the key itself is never an argument.
#include <signal.h>
#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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

int usage(const std::string& problem) {
  std::fprintf(stderr,
               "error: %s\n"
               "usage: torsion_haptic_peer --trajectory FILE [--port P] [--host 127.0.0.1] "
               "[--rate HZ] [--log FILE] [--key-file FILE]\n",
               problem.c_str());
  return 1;
}

// Whole-string numbers only: "12abc" or "" is an error, not 12 or 0.
bool parseNumber(const char* text, double& out) {
  char* end = nullptr;
  out = std::strtod(text, &end);
  return end != text && *end == '\0' && std::isfinite(out);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace torsion::device;
  std::string trajectory_path, log_path, host = "127.0.0.1";
  int port = 5750;
  double rate = 1000;
  std::string key_path;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    const bool has_value = k + 1 < argc;
    double number = 0;
    if (a == "--trajectory" && has_value) {
      trajectory_path = argv[++k];
    } else if (a == "--port" && has_value) {
      if (!parseNumber(argv[++k], number) || number != std::floor(number) || number < 1 ||
          number > 65535)
        return usage("--port: expected a whole number in [1, 65535]");
      port = static_cast<int>(number);
    } else if (a == "--host" && has_value) {
      host = argv[++k];
    } else if (a == "--rate" && has_value) {
      if (!parseNumber(argv[++k], number) || !(number > 0) || number > 1e6)
        return usage("--rate: expected a number of Hz in (0, 1e6]");
      rate = number;
    } else if (a == "--log" && has_value) {
      log_path = argv[++k];
    } else if (a == "--key-file" && has_value) {
      key_path = argv[++k];
    } else if (a == "--key") {
      return usage(
          "--key: a key on the command line is visible to every local user; put it in "
          "a file (--key-file) or in TORSION_HAPTIC_KEY");
    } else {
      return usage(has_value || a.rfind("--", 0) != 0 ? "unexpected argument '" + a + "'"
                                                      : a + " needs a value");
    }
  }
  if (trajectory_path.empty()) return usage("--trajectory is required");
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
      const Wrench& w = p.newestWrench();
      log << t << ',' << w.force.x << ',' << w.force.y << ',' << w.force.z << ',' << w.torque.x
          << ',' << w.torque.y << ',' << w.torque.z << ',' << p.newestEcho() << '\n';
    }
  }
  p.sayGoodbye(monotonicSeconds() - origin);  // frees the simulation's device for another peer
  const PacketStats& s = p.stats();
  std::fprintf(stderr,
               "peer: sent %llu poses, accepted %llu wrenches, rejected %llu (unauthenticated "
               "%llu, other session %llu)\n",
               static_cast<unsigned long long>(s.sent.load()),
               static_cast<unsigned long long>(s.accepted.load()),
               static_cast<unsigned long long>(s.rejected()),
               static_cast<unsigned long long>(s.unauthenticated.load()),
               static_cast<unsigned long long>(s.replayed.load()));
  return 0;
}
