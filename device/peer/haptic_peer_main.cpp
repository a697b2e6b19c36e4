// torsion_haptic_peer: the reference peer of the network device. It stands where a vendor's
// force-feedback driver would: it sends the poses of a scripted trajectory to the simulation at
// a fixed rate over UDP and receives the wrenches to render (docs/haptics.md, "Packet format").
//
//   torsion_haptic_peer --trajectory assets/trajectories/figure_6_7.json [--port 5750]
//                       [--rate 1000] [--log received.csv]
#include <time.h>  // NOLINT(modernize-deprecated-headers): POSIX clock_gettime and friends

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>

#include "torsion/device/network_peer.h"
#include "torsion/device/trajectory.h"

namespace {

double monotonicSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

int usage() {
  std::fprintf(stderr,
               "usage: torsion_haptic_peer --trajectory FILE [--port P] [--host 127.0.0.1] "
               "[--rate HZ] [--log FILE]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace torsion::device;
  std::string trajectory_path, log_path, host = "127.0.0.1";
  int port = 5750;
  double rate = 1000;
  for (int k = 1; k < argc; ++k) {
    const std::string a = argv[k];
    const bool has_value = k + 1 < argc;
    if (a == "--trajectory" && has_value) {
      trajectory_path = argv[++k];
    } else if (a == "--port" && has_value) {
      port = std::atoi(argv[++k]);
    } else if (a == "--host" && has_value) {
      host = argv[++k];
    } else if (a == "--rate" && has_value) {
      rate = std::atof(argv[++k]);
    } else if (a == "--log" && has_value) {
      log_path = argv[++k];
    } else {
      return usage();
    }
  }
  if (trajectory_path.empty() || port <= 0 || port > 65535 || !(rate > 0)) return usage();
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
  auto peer = NetworkPeer::open(simulation, *trajectory.value);
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
  std::fprintf(stderr, "peer: sending %s to %s:%d at %.0f Hz for %.1f s\n", trajectory_path.c_str(),
               host.c_str(), port, rate, duration);
  const double origin = monotonicSeconds();
  for (long k = 0;; ++k) {
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
  std::fprintf(stderr, "peer: sent %llu poses, accepted %llu wrenches, rejected %llu\n",
               static_cast<unsigned long long>(s.sent.load()),
               static_cast<unsigned long long>(s.accepted.load()),
               static_cast<unsigned long long>(s.rejected()));
  return 0;
}
