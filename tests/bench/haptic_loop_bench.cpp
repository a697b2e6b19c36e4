// Haptic loop benchmark and headless Figure 6.7 runs. Not a test: it measures.
//
//   bench_haptic_loop threaded MESH_TETS SECONDS [LOG.csv] [--priority P] [--kh-columns N]
//                     [--kh-refresh N] [--threads N] [--free-running] [--steps N]
//                     [--sim-priority P]
//       The 1 kHz loop on its own thread (scripted Figure 6.7 device) while the simulation thread
//       steps the cylinder on 2 solver threads, paced to the clock as an interactive run is
//       (--free-running: as fast as it can); prints loop rate, period jitter p50/p99/max,
//       overruns, wrench age (since the simulation's wrench arrived) and information age (of the
//       newest information in the rendered wrench: the device pose the K_h prediction used, or
//       without K_h the pose the step used), simulation step time p50/p99/max (the step alone,
//       not the pacing's wait; its CPU time on the stepping thread, which the machine's load
//       does not inflate as much), CG iterations per step, steps per second, the 1-minute load
//       average, and whether the loop got SCHED_FIFO. --priority 0 keeps the default
//       scheduling (default: the loop's 80); --sim-priority P the stepping thread's SCHED_FIFO
//       priority (default 50, HapticRuntime::setSimulationPriority; 0: the default policy);
//       --kh-columns 6 refreshes K_h in one step (default 1
//       column per step); --kh-refresh 0 publishes no K_h; --steps N stops after N steps.
//       TORSION_BENCH_STEP_TIMES=FILE writes each step's milliseconds and CG iterations.
//   bench_haptic_loop figure67 internal_force|frame_difference LOG.csv [MESH_TETS]
//       The Figure 6.7 sequence on a simulated clock (lockstep, deterministic), loop log to CSV
//       for docs/haptics.md (tests/bench/plot_haptics.py draws it).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <vector>

#include "torsion/bullet/fem_world.h"
#include "torsion/bullet/hand.h"
#include "torsion/device/scripted_device.h"
#include "torsion/haptics/hand_coupling.h"
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

Cylinder makeCylinder(int tets, haptics::Rendering rendering, int threads, int kh_columns = 1,
                      int kh_refresh = 10) {
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
  settings.stiffness_refresh_steps = kh_refresh;
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

// CPU seconds of the calling thread (a step's own work on it, whatever the machine's load).
double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The 1-minute load average (state it with any wall-clock figure on a shared machine).
double loadAverage() {
  double load = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &load) != 1) load = -1;
    std::fclose(f);
  }
  return load;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1))];
}

struct ThreadedOptions {
  int priority = device::HapticLoopSettings{}.realtime_priority;
  int kh_columns = 1;
  int kh_refresh = 10;
  int solver_threads = 2;  // as the plain twist benchmark's 2-thread rows
  bool real_time = true;   // paced to the clock, as an interactive run (torsion run --haptics)
  int sim_priority = 50;   // SCHED_FIFO priority of the stepping thread (0: the default policy)
  int steps = 0;  // > 0: stop after this many steps (instruction counts per step), not SECONDS
};

int threaded(int tets, double seconds, const char* log_path, const ThreadedOptions& o) {
  Cylinder c = makeCylinder(tets, haptics::Rendering::kInternalForce, o.solver_threads,
                            o.kh_columns, o.kh_refresh);
  device::ScriptedDevice scripted(figure67(), device::defaultDeviceLimits(), "figure_6_7");
  device::HapticLoopSettings settings;
  settings.log_capacity = static_cast<size_t>(seconds * 1000 * 1.2) + 1000;
  settings.realtime_priority = o.priority;
  device::HapticLoop loop(scripted, settings);
  haptics::HapticRuntime runtime(*c.world, {{c.coupling.get(), &loop, 1000}});
  // The step alone is timed (the pacing's wait, when real time, is not part of it).
  int steps = 0;
  std::vector<double> step_ms, step_cpu_ms, step_iterations;
  runtime.setSimulationPriority(o.sim_priority);
  runtime.startThreads();
  const bool sim_realtime = runtime.simulationRealtime();
  const auto start = std::chrono::steady_clock::now();
  while (o.steps > 0
             ? steps < o.steps
             : std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() <
                   seconds) {
    if (o.real_time) runtime.pace();
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = threadCpuSeconds();
    const WorldStepReport report = runtime.step();
    step_cpu_ms.push_back(1e3 * (threadCpuSeconds() - cpu0));
    step_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    step_iterations.push_back(static_cast<double>(c.body->lastReport().solve.iterations));
    ++steps;
    if (!report.ok) {
      std::fprintf(stderr, "unstable: %s\n", report.message.c_str());
      break;
    }
  }
  runtime.stopThreads();
  if (const char* dump = std::getenv("TORSION_BENCH_STEP_TIMES")) {
    if (FILE* f = std::fopen(dump, "w")) {
      for (size_t k = 0; k < step_ms.size(); ++k)
        std::fprintf(f, "%.4f %g\n", step_ms[k], step_iterations[k]);
      std::fclose(f);
    }
  }
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
      "%.2f, \"p99\": %.2f, \"max\": %.2f}, \"sim_step_cpu_ms_this_thread\": {\"p50\": %.2f, "
      "\"p99\": %.2f}, \"load_1min\": %.2f, \"cg_iterations_per_step\": {\"p50\": %.0f, \"p99\": "
      "%.0f}, \"solver_threads\": %d, "
      "\"real_time\": %s, \"kh_columns_per_step\": %d, \"kh_refresh_steps\": %d, "
      "\"realtime\": %s, \"sim_priority\": %d, \"sim_realtime\": %s}\n",
      tets, wall, span > 0 ? static_cast<double>(log.size() - 1) / span : 0.0,
      percentile(period_error, 0.5), percentile(period_error, 0.99), percentile(period_error, 1.0),
      percentile(period, 0.5), percentile(period, 0.99),
      static_cast<unsigned long long>(loop.stats().overruns.load()), percentile(age, 0.5),
      percentile(age, 0.99), percentile(age, 1.0), percentile(information_age, 0.5),
      percentile(information_age, 0.99), percentile(information_age, 1.0), steps / wall,
      percentile(step_ms, 0.5), percentile(step_ms, 0.99), percentile(step_ms, 1.0),
      percentile(step_cpu_ms, 0.5), percentile(step_cpu_ms, 0.99), loadAverage(),
      percentile(step_iterations, 0.5), percentile(step_iterations, 0.99), o.solver_threads,
      o.real_time ? "true" : "false", o.kh_columns, o.kh_refresh,
      loop.stats().realtime ? "true" : "false", o.sim_priority, sim_realtime ? "true" : "false");
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
    ThreadedOptions options;
    for (int k = 4; k < argc; ++k) {
      const std::string a = argv[k];
      if (a == "--priority" && k + 1 < argc) {
        options.priority = std::atoi(argv[++k]);
      } else if (a == "--kh-columns" && k + 1 < argc) {
        options.kh_columns = std::atoi(argv[++k]);
      } else if (a == "--kh-refresh" && k + 1 < argc) {
        options.kh_refresh = std::atoi(argv[++k]);
      } else if (a == "--threads" && k + 1 < argc) {
        options.solver_threads = std::atoi(argv[++k]);
      } else if (a == "--steps" && k + 1 < argc) {
        options.steps = std::atoi(argv[++k]);
      } else if (a == "--sim-priority" && k + 1 < argc) {
        options.sim_priority = std::atoi(argv[++k]);
      } else if (a == "--free-running") {
        options.real_time = false;
      } else {
        log = argv[k];
      }
    }
    return threaded(std::atoi(argv[2]), std::atof(argv[3]), log, options);
  }
  if (mode == "figure67" && argc >= 4) {
    return figure(argv[2], argv[3], argc > 4 ? std::atoi(argv[4]) : 2430);
  }
  std::fprintf(
      stderr,
      "usage: bench_haptic_loop threaded TETS SECONDS [LOG.csv] [--priority P] [--kh-columns N]\n"
      "                         [--kh-refresh N] [--threads N] [--free-running] [--steps N]\n"
      "                         [--sim-priority P]\n"
      "       bench_haptic_loop figure67 internal_force|frame_difference LOG.csv [TETS]\n");
  return 2;
}
