// Haptic loop benchmark and headless Figure 6.7 runs. Not a test: it measures.
//
//   bench_haptic_loop threaded MESH_TETS SECONDS [LOG.csv] [--priority P] [--kh-columns N]
//       The 1 kHz loop on its own thread (scripted Figure 6.7 device) while the simulation thread
//       steps the cylinder as fast as it can; prints loop rate, period jitter p50/p99/max,
//       overruns, wrench age (since the simulation's wrench arrived) and information age (of the
//       newest information in the rendered wrench: the device pose the K_h prediction used, or
//       without K_h the pose the step used), simulation step time p50/p99/max and steps per second,
//       and whether the loop got SCHED_FIFO. --priority 0 keeps the default scheduling (default:
//       the loop's 80); --kh-columns 6 refreshes K_h in one step (default 1 column per step).
//   bench_haptic_loop figure67 internal_force|frame_difference LOG.csv [MESH_TETS]
//       The Figure 6.7 sequence on a simulated clock (lockstep, deterministic), loop log to CSV
//       for docs/haptics.md (tests/bench/plot_haptics.py draws it).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/device/scripted_device.h"
#include "torsion/haptics/haptic_runtime.h"
#include "torsion/mesh/mesh_io.h"

namespace {

using namespace torsion;

struct Cylinder {
  std::unique_ptr<FemWorld> world;
  FemBody* body = nullptr;
  std::unique_ptr<Hand> hand;
  std::unique_ptr<haptics::HandCoupling> coupling;
};

Cylinder makeCylinder(int tets, haptics::Rendering rendering, int threads, int kh_columns = 1) {
  Result<LoadedMesh> mesh =
      readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_" + std::to_string(tets) + ".node");
  if (!mesh) {
    std::fprintf(stderr, "error: %s\n", mesh.error().message.c_str());
    std::exit(1);
  }
  WorldSettings ws;  // the twist scenes: dt = 0.01, CG, block Jacobi, 1e-4
  ws.gravity.setZero();
  ws.solver.threads = threads;
  Cylinder c;
  c.world = std::make_unique<FemWorld>(ws);
  Material material;
  material.stiffness_damping = 0.01;
  const TetMesh& m = mesh.value().mesh;
  c.body = c.world->addBody("cylinder", m, material).value();
  std::vector<int> base;
  for (int i = 0; i < m.nodeCount(); ++i) {
    if (std::abs(m.restPositions()[static_cast<size_t>(i)].z()) < 1e-6) base.push_back(i);
  }
  c.body->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0);
  c.hand = std::make_unique<Hand>(*c.body);
  haptics::DeviceMapping mapping;
  mapping.anchor.origin = Eigen::Vector3d(0, 0, 9.9);
  mapping.position_scale = 10;  // 5 cm on the desk: 0.5 m on the 10 m cylinder
  haptics::CouplingSettings settings;
  settings.rendering = rendering;
  settings.stiffness_columns_per_step = kh_columns;
  c.coupling = std::make_unique<haptics::HandCoupling>(*c.hand, mapping, settings);
  return c;
}

device::Trajectory figure67() {
  auto t = device::loadTrajectory(TORSION_TRAJECTORIES_DIR "/figure_6_7.json");
  if (!t) {
    std::fprintf(stderr, "error: %s\n", t.error.c_str());
    std::exit(1);
  }
  return *t.value;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1))];
}

int threaded(int tets, double seconds, const char* log_path, int priority, int kh_columns) {
  Cylinder c = makeCylinder(tets, haptics::Rendering::kInternalForce, 1, kh_columns);
  device::ScriptedDevice scripted(figure67(), device::defaultDeviceLimits(), "figure_6_7");
  device::HapticLoopSettings settings;
  settings.log_capacity = static_cast<size_t>(seconds * 1000 * 1.2) + 1000;
  settings.realtime_priority = priority;
  device::HapticLoop loop(scripted, settings);
  haptics::HapticRuntime runtime(*c.world, {{c.coupling.get(), &loop, 1000}});
  const auto start = std::chrono::steady_clock::now();
  int steps = 0;
  std::vector<double> step_ms;
  auto previous = start;
  runtime.runThreaded(1 << 30, false, [&](const WorldStepReport&) {
    ++steps;
    const auto now = std::chrono::steady_clock::now();
    if (steps > 1)
      step_ms.push_back(std::chrono::duration<double, std::milli>(now - previous).count());
    previous = now;
    return std::chrono::duration<double>(now - start).count() < seconds;
  });
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<double> period_error, period, age, information_age;
  for (size_t k = 1; k < loop.log().size(); ++k) {
    const device::LoopLogRow& r = loop.log()[k];
    period_error.push_back(std::abs(r.period - 0.001) * 1e3);
    period.push_back(r.period * 1e3);
    if (r.sim_step > 0) age.push_back(r.wrench_age * 1e3);
    // Only while a patch is held: the age of what the device feels.
    if (r.sim_step > 0 && r.grabbed) information_age.push_back(r.information_age * 1e3);
  }
  const auto& log = loop.log();
  const double span = log.size() > 1 ? log.back().time - log.front().time : 0;
  std::printf(
      "{\"tets\": %d, \"seconds\": %.1f, \"loop_rate_hz\": %.1f, \"period_error_ms\": {\"p50\": "
      "%.4f, \"p99\": %.4f, \"max\": %.3f}, \"period_ms\": {\"p50\": %.4f, \"p99\": %.4f}, "
      "\"overruns\": %llu, \"wrench_age_ms\": {\"p50\": "
      "%.2f, \"p99\": %.2f, \"max\": %.2f}, \"information_age_ms\": {\"p50\": %.2f, \"p99\": "
      "%.2f, \"max\": %.2f}, \"sim_steps_per_s\": %.1f, \"sim_step_ms\": {\"p50\": "
      "%.2f, \"p99\": %.2f, \"max\": %.2f}, \"kh_columns_per_step\": %d, \"realtime\": %s}\n",
      tets, wall, span > 0 ? static_cast<double>(log.size() - 1) / span : 0.0,
      percentile(period_error, 0.5), percentile(period_error, 0.99), percentile(period_error, 1.0),
      percentile(period, 0.5), percentile(period, 0.99),
      static_cast<unsigned long long>(loop.stats().overruns.load()), percentile(age, 0.5),
      percentile(age, 0.99), percentile(age, 1.0), percentile(information_age, 0.5),
      percentile(information_age, 0.99), percentile(information_age, 1.0), steps / wall,
      percentile(step_ms, 0.5), percentile(step_ms, 0.99), percentile(step_ms, 1.0), kh_columns,
      loop.stats().realtime ? "true" : "false");
  if (log_path && !loop.writeLog(log_path)) return 1;
  return 0;
}

int figure(const std::string& rendering, const char* log_path, int tets) {
  const auto r = rendering == "frame_difference" ? haptics::Rendering::kFrameDifference
                                                 : haptics::Rendering::kInternalForce;
  Cylinder c = makeCylinder(tets, r, 0);
  const device::Trajectory trajectory = figure67();
  device::ScriptedDevice scripted(trajectory, device::defaultDeviceLimits(), "figure_6_7");
  device::HapticLoopSettings settings;
  settings.log_capacity = static_cast<size_t>(trajectory.duration() * 1000) + 2000;
  device::HapticLoop loop(scripted, settings);
  haptics::HapticRuntime runtime(*c.world, {{c.coupling.get(), &loop, 1000}});
  const int steps = static_cast<int>(std::ceil((trajectory.duration() + 0.5) / 0.01));
  for (int k = 0; k < steps; ++k) {
    const WorldStepReport report = runtime.stepLockstep();
    if (!report.ok) {
      std::fprintf(stderr, "unstable: %s\n", report.message.c_str());
      return 3;
    }
  }
  for (const std::string& w : runtime.warnings())
    std::fprintf(stderr, "warning: %s\n", w.c_str());
  return loop.writeLog(log_path) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "threaded" && argc >= 4) {
    const char* log = nullptr;
    int priority = device::HapticLoopSettings{}.realtime_priority, kh_columns = 1;
    for (int k = 4; k < argc; ++k) {
      const std::string a = argv[k];
      if (a == "--priority" && k + 1 < argc) {
        priority = std::atoi(argv[++k]);
      } else if (a == "--kh-columns" && k + 1 < argc) {
        kh_columns = std::atoi(argv[++k]);
      } else {
        log = argv[k];
      }
    }
    return threaded(std::atoi(argv[2]), std::atof(argv[3]), log, priority, kh_columns);
  }
  if (mode == "figure67" && argc >= 4) {
    return figure(argv[2], argv[3], argc > 4 ? std::atoi(argv[4]) : 2430);
  }
  std::fprintf(
      stderr,
      "usage: bench_haptic_loop threaded TETS SECONDS [LOG.csv] [--priority P] [--kh-columns N]\n"
      "       bench_haptic_loop figure67 internal_force|frame_difference LOG.csv [TETS]\n");
  return 2;
}
