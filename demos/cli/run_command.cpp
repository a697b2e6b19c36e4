#include "run_command.h"

#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "device_options.h"
#include "frame_recorder.h"
#include "progress_bar.h"
#include "scene_haptics.h"
#include "scene_parser.h"
#include "scene_runner.h"
#include "torsion/device/json_check.h"
#include "torsion/solve/parallel.h"
#include "verbosity.h"
#include "vtk_series.h"

namespace torsion::cli {

namespace {

struct RunArguments {
  std::string scene;
  std::string out = "results";
  int steps = -1;
  int threads = -1;
  std::string render;  // --render DIR: PNG pictures (and an MP4 with ffmpeg)
  std::string render_size = "800x600";
  int render_every = 10;
  bool stop_on_anomaly = false;
  int vtk_every = -1;  // --vtk-every N: a ParaView series every N steps (vtk_series.h); -1: scene's
  scene::DeviceOverrides devices;  // --device HAND=TYPE[:ARG] (repeatable), --haptics MODE
};

// The signal that asked the run to stop, 0 while none has. Written by the handler only.
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void requestStop(int signal) {
  g_stop_signal = signal;
}

// SIGINT and SIGTERM stop the run at the end of the current step (scene_runner.h) while this
// object lives; the previous handlers come back afterwards. A signal the process was started
// ignoring (a background job of a non-interactive shell ignores SIGINT, nohup SIGHUP) stays
// ignored, as is the convention.
class StopOnSignals {
 public:
  StopOnSignals() {
    catchUnlessIgnored(SIGINT, previous_int_);
    catchUnlessIgnored(SIGTERM, previous_term_);
  }
  ~StopOnSignals() {
    sigaction(SIGINT, &previous_int_, nullptr);
    sigaction(SIGTERM, &previous_term_, nullptr);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

 private:
  static void catchUnlessIgnored(int signal, struct sigaction& previous) {
    sigaction(signal, nullptr, &previous);
    if (previous.sa_handler == SIG_IGN) return;
    struct sigaction action {};
    action.sa_handler = requestStop;
    sigemptyset(&action.sa_mask);
    sigaction(signal, &action, nullptr);
  }

  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
};

// Exit codes: 0 done and stable, 1 bad input or output error, 3 the simulation went unstable,
// 4 stopped at an anomaly (--stop-on-anomaly), 128 + signal when SIGINT (130) or SIGTERM (143)
// stopped the run.
int run(const RunArguments& args) {
  Result<scene::SceneSpec> spec = scene::loadScene(args.scene);
  if (!spec) {
    std::cerr << "error: " << spec.error().message << "\n";
    return 1;
  }
  if (Status applied = scene::applyDeviceOverrides(spec.value(), args.devices); !applied) {
    std::cerr << "error: " << applied.error().message << "\n";
    return 1;
  }
  for (const std::string& w : scene::remoteDeviceWarnings(spec.value()))
    std::cerr << "warning: " << w << "\n";
  Result<std::unique_ptr<scene::BuiltScene>> built =
      scene::buildScene(std::move(spec).value(), args.threads);
  if (!built) {
    std::cerr << "error: " << built.error().message << "\n";
    return 1;
  }
  scene::BuiltScene& s = *built.value();
  for (const std::string& w : s.warnings)
    std::cerr << "warning: " << w << "\n";
  if (const int asked = s.world->settings().solver.threads;
      asked > 0 && Parallel::usableThreads(asked) < asked) {
    std::cerr << "warning: " << asked << " threads asked for, the machine has "
              << Parallel::usableThreads(asked) << " cores: using "
              << Parallel::usableThreads(asked) << "\n";
  }
  const bool normal = verbosity() != Verbosity::kQuiet;
  if (verbosity() == Verbosity::kVerbose) {
    const SolverSettings& solver = s.world->settings().solver;
    std::cerr << "scene '" << device::printableExcerpt(s.spec.name) << "' from "
              << device::printableExcerpt(s.spec.file, 200) << ": "
              << (args.steps > 0 ? args.steps : s.spec.steps)
              << " steps of dt = " << solver.time_step << " s, " << toString(solver.linear_solver)
              << " solver (tolerance " << solver.tolerance << "), "
              << Parallel::usableThreads(solver.threads) << " threads; output in "
              << device::printableExcerpt(args.out, 200) << "/\n";
  }
  for (const auto& body : s.world->bodies()) {
    if (!normal) break;
    std::cerr << "body '" << body->name() << "': " << body->model().nodeCount() << " nodes, "
              << body->model().elementCount()
              << (body->model().elementKind() == ElementKind::kTet10 ? " tet10 elements\n"
                                                                     : " tets\n");
  }
  if (s.haptics && normal) {
    for (const std::string& line : s.haptics->describe())
      std::cerr << line << "\n";
  }

  std::unique_ptr<render::FrameRecorder> recorder;
  if (!args.render.empty()) {
    render::RecorderOptions ro;
    ro.directory = args.render;
    ro.every = args.render_every;
    if (std::sscanf(args.render_size.c_str(), "%dx%d", &ro.width, &ro.height) != 2) {
      std::cerr << "error: --render-size '" << args.render_size
                << "': expected WxH, e.g. 800x600\n";
      return 1;
    }
    Result<std::unique_ptr<render::FrameRecorder>> made = render::FrameRecorder::create(ro);
    if (!made) {
      std::cerr << "error: --render: " << made.error().message << "\n";
      return 1;
    }
    recorder = std::move(made).value();
    if (Status drawn = recorder->capture(s, 0); !drawn) {
      std::cerr << "error: --render: " << drawn.error().message << "\n";
      return 1;
    }
  }

  std::unique_ptr<VtkSeries> series;
  if (const int every = args.vtk_every >= 0 ? args.vtk_every : s.spec.vtk_every; every > 0) {
    Result<std::unique_ptr<VtkSeries>> started = VtkSeries::start(args.out, every, s);
    if (!started) {
      std::cerr << "error: --vtk-every: " << started.error().message << "\n";
      return 1;
    }
    series = std::move(started).value();
  }
  std::string series_error;

  ProgressBar bar(device::printableExcerpt(s.spec.name));  // the label goes out through stdio
  scene::RunOptions options;
  options.output_directory = args.out;
  options.steps = args.steps;
  options.stop_on_anomaly = args.stop_on_anomaly;
  if (series) options.extra_outputs.push_back("series.pvd");
  std::string render_error;
  options.progress = [&](int done, int total, double rate) {
    if (normal) bar.update(done, total, rate);
    if (recorder && render_error.empty()) {
      Status drawn = done == total ? recorder->capture(s, rate) : recorder->onStep(s, rate);
      if (!drawn) render_error = drawn.error().message;
    }
    if (series && series_error.empty()) {
      Status written = series->onStep(s, done, total);
      if (!written) series_error = written.error().message;
    }
  };
  options.stop_requested = [] { return static_cast<int>(g_stop_signal); };
  Result<scene::RunOutcome> outcome = Error{};
  {
    StopOnSignals stop_on_signals;
    outcome = scene::runScene(s, options);
  }
  if (normal) bar.finish();
  if (!outcome) {
    std::cerr << "error: " << outcome.error().message << "\n";
    return 1;
  }
  if (!series_error.empty()) {
    std::cerr << "error: --vtk-every: " << series_error << "\n";
    return 1;
  }
  if (!render_error.empty()) {
    std::cerr << "error: --render: " << render_error << "\n";
    return 1;
  }
  if (s.haptics) {
    for (const std::string& w : s.haptics->warnings())
      std::cerr << "warning: haptics: " << w << "\n";
  }
  if (series && normal)
    std::cerr << "series: " << args.out << "/series.pvd (" << series->stepsWritten()
              << " steps, open in ParaView)\n";
  if (recorder) {  // finish() also makes the video: always, whatever is printed
    const std::string pictures = recorder->finish(s.spec.name);
    if (normal) std::cerr << "pictures: " << pictures << "\n";
  }
  if (const int signal = outcome.value().stopped_by; signal != 0) {
    std::cerr << "stopped by " << (signal == SIGINT ? "SIGINT" : "SIGTERM") << " after "
              << outcome.value().steps_done << " steps; results so far in " << args.out
              << "/ (summary.json says \"completed\": false)\n";
    return 128 + signal;
  }
  if (!outcome.value().stable) {
    std::cerr << "error: simulation unstable: " << outcome.value().failure << "\n"
              << "results up to the last good step are in " << args.out << "/\n";
    return 3;
  }
  if (!outcome.value().stopped_on_anomaly.empty()) {
    std::cerr << "error: stopped at the first anomaly: " << outcome.value().stopped_on_anomaly
              << "\nresults up to that step are in " << args.out << "/\n";
    return 4;
  }
  if (!normal) return 0;
  std::cerr << "done: " << outcome.value().steps_done << " steps; results in " << args.out
            << "/ (summary.json, wrench.csv, energy.csv, "
            << (s.rigid_bodies.empty() ? "" : "rigid.csv, ") << "one .vtk per body"
            << (s.haptics ? ", haptic_<hand>.csv per device hand" : "") << ")\n";
  return 0;
}

}  // namespace

void addRunCommand(CLI::App& app, CommandAction& chosen) {
  auto args = std::make_shared<RunArguments>();
  CLI::App* cmd = app.add_subcommand("run", "Run a scene headless and write its results");
  cmd->add_option("scene", args->scene,
                  "Scene file (JSON, see docs/scene-format.md) or the name of a demo scene (drop, "
                  "twist_cylinder_2430, ...)")
      ->required();
  cmd->add_option("--out", args->out, "Output directory")->capture_default_str();
  // Ranges with readable bounds (CLI::PositiveNumber prints the double range in 300 digits).
  cmd->add_option("--steps", args->steps, "Number of steps (default: the scene's)")
      ->check(CLI::Range(1, 2000000000).description("an integer from 1 to 2000000000"));
  cmd->add_option("--threads", args->threads,
                  "Worker threads (default: the scene's; 0 = all cores)")
      ->check(CLI::Range(0, 4096).description("an integer from 0 to 4096"));
  cmd->add_option("--render", args->render,
                  "Also draw the scene (OSMesa) into PNG pictures in this directory, and an MP4 "
                  "when ffmpeg is on PATH");
  cmd->add_option("--render-size", args->render_size, "Picture size WxH")->capture_default_str();
  cmd->add_option("--render-every", args->render_every, "Steps between pictures")
      ->check(CLI::Range(1, 1000000000).description("an integer from 1 to 1000000000"))
      ->capture_default_str();
  cmd->add_flag("--stop-on-anomaly", args->stop_on_anomaly,
                "Stop at the first anomaly (inverted tets, released elastic energy, node speed "
                "burst) with exit code 4");
  cmd->add_option("--vtk-every", args->vtk_every,
                  "Also write a ParaView time series (series.pvd, one .vtu per body per written "
                  "step) every N steps; 0: none (default: the scene's vtk_every, else none)")
      ->check(CLI::Range(0, 2000000000).description("an integer from 0 to 2000000000"));
  addDeviceOptions(*cmd, args->devices);
  cmd->callback([&chosen, args] { chosen = [args] { return run(*args); }; });
}

}  // namespace torsion::cli
