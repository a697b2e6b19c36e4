#include "run_command.h"

#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "cli_messages.h"
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

using series::VtkSeries;

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
  scene::DeviceOverrides devices;  // --device NAME=TYPE[:ARG] (repeatable), --haptics MODE
};

// The signal that asked the run to stop, 0 while none has. Written by the handler only.
volatile std::sig_atomic_t g_stop_signal = 0;

extern "C" void requestStop(int signal) {
  g_stop_signal = signal;
}

// SIGINT, SIGTERM and SIGHUP (the terminal or ssh session closed) stop the run at the end of the
// current step (scene_runner.h) while this object lives: a device hand's force then fades and
// the device gets a zero wrench, and the directory is left consistent. The previous handlers
// come back afterwards. A signal the process was started ignoring (a background job of a
// non-interactive shell ignores SIGINT, nohup SIGHUP) stays ignored, as is the convention.
class StopOnSignals {
 public:
  StopOnSignals() {
    catchUnlessIgnored(SIGINT, previous_int_);
    catchUnlessIgnored(SIGTERM, previous_term_);
    catchUnlessIgnored(SIGHUP, previous_hup_);
  }
  ~StopOnSignals() {
    sigaction(SIGINT, &previous_int_, nullptr);
    sigaction(SIGTERM, &previous_term_, nullptr);
    sigaction(SIGHUP, &previous_hup_, nullptr);
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
  struct sigaction previous_hup_ {};
};

// The scene file, with --device / --haptics applied, built into a live world.
Result<std::unique_ptr<scene::BuiltScene>> loadAndBuild(const RunArguments& args) {
  Result<scene::SceneSpec> spec = scene::loadScene(args.scene);
  if (!spec) return spec.error();
  if (Status applied = scene::applyDeviceOverrides(spec.value(), args.devices); !applied)
    return applied.error();
  for (const std::string& w : scene::remoteDeviceWarnings(spec.value()))
    std::cerr << "warning: " << w << "\n";
  return scene::buildScene(std::move(spec).value(), scene::BuildOptions{args.threads});
}

// On stderr: the build's warnings, the threads used, and unless --quiet each body's size and each
// device hand (--verbose: the run's settings too).
void describe(const RunArguments& args, const scene::BuiltScene& s) {
  for (const std::string& w : s.warnings)
    std::cerr << "warning: " << w << "\n";
  if (const int asked = s.world->settings().solver.threads;
      asked > 0 && Parallel::usableThreads(asked) < asked) {
    std::cerr << "warning: " << asked << " threads asked for, the machine has "
              << Parallel::usableThreads(asked) << " cores: using "
              << Parallel::usableThreads(asked) << "\n";
  }
  if (verbosity() == Verbosity::kQuiet) return;
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
    std::cerr << "body '" << body->name() << "': " << body->model().nodeCount() << " nodes, "
              << body->model().elementCount()
              << (body->model().elementKind() == ElementKind::kTet10 ? " tet10 elements\n"
                                                                     : " tets\n");
  }
  if (s.haptics) {
    for (const std::string& line : s.haptics->describe())
      std::cerr << line << "\n";
  }
}

// --render DIR: the recorder with the first picture taken (null without --render).
Result<std::unique_ptr<render::FrameRecorder>> startRecorder(const RunArguments& args,
                                                             scene::BuiltScene& s) {
  if (args.render.empty()) return std::unique_ptr<render::FrameRecorder>();
  render::RecorderOptions ro;
  ro.directory = args.render;
  ro.every = args.render_every;
  if (std::sscanf(args.render_size.c_str(), "%dx%d", &ro.width, &ro.height) != 2)
    return Error{"--render-size '" + args.render_size + "': expected WxH, e.g. 800x600"};
  Result<std::unique_ptr<render::FrameRecorder>> made = render::FrameRecorder::create(ro);
  if (!made) return Error{"--render: " + made.error().message};
  if (Status drawn = made.value()->capture(s, 0); !drawn)
    return Error{"--render: " + drawn.error().message};
  return made;
}

// --vtk-every N (or the scene's vtk_every): the ParaView series started (null without one).
Result<std::unique_ptr<VtkSeries>> startSeries(const RunArguments& args, scene::BuiltScene& s) {
  const int every = args.vtk_every >= 0 ? args.vtk_every : s.spec.vtk_every;
  if (every <= 0) return std::unique_ptr<VtkSeries>();
  Result<std::unique_ptr<VtkSeries>> started = VtkSeries::start(args.out, every, s);
  if (!started) return Error{"--vtk-every: " + started.error().message};
  return started;
}

struct Ran {
  Result<scene::RunOutcome> outcome = Error{};
};

// The headless run with a progress bar, a picture every --render-every steps, and SIGINT /
// SIGTERM / SIGHUP stopping it at the end of a step. A picture or series step that cannot be
// written stops the run as an output error (summary.json says so).
Ran runWithProgress(const RunArguments& args, scene::BuiltScene& s, render::FrameRecorder* recorder,
                    VtkSeries* series) {
  Ran ran;
  const bool normal = verbosity() != Verbosity::kQuiet;
  ProgressBar bar(device::printableExcerpt(s.spec.name));  // the label goes out through stdio
  scene::RunOptions options;
  options.output_directory = args.out;
  options.steps = args.steps;
  options.stop_on_anomaly = args.stop_on_anomaly;
  if (series) options.extra_outputs.push_back("series.pvd");
  options.write_step_outputs = [&](int done, int total, double rate) -> Status {
    if (recorder) {
      Status drawn = done == total ? recorder->capture(s, rate) : recorder->onStep(s, rate);
      if (!drawn) return Error{"--render: " + drawn.error().message};
    }
    if (series) {
      Status written = series->onStep(s, done, total);
      if (!written) return Error{"--vtk-every: " + written.error().message};
    }
    return Ok{};
  };
  options.progress = [&](int done, int total, double rate) {
    if (normal) bar.update(done, total, rate);
  };
  options.stop_requested = [] { return static_cast<int>(g_stop_signal); };
  {
    StopOnSignals stop_on_signals;
    ran.outcome = scene::runScene(s, options);
  }
  if (normal) bar.finish();
  return ran;
}

// Exit codes: 0 done and stable, 1 bad input or output error, 3 the simulation went unstable,
// 4 stopped at an anomaly (--stop-on-anomaly), 128 + signal when SIGHUP (129), SIGINT (130) or
// SIGTERM (143) stopped the run.
int reportOutcome(const RunArguments& args, const scene::BuiltScene& s, const Ran& ran,
                  render::FrameRecorder* recorder, const VtkSeries* series) {
  const bool normal = verbosity() != Verbosity::kQuiet;
  if (!ran.outcome) return fail(ran.outcome.error().message);
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
  const scene::RunOutcome& outcome = ran.outcome.value();
  if (const int signal = outcome.stopped_by; signal != 0) {
    std::cerr << "stopped by " << scene::signalName(signal) << " after " << outcome.steps_done
              << " steps; results so far in " << args.out
              << "/ (summary.json says \"completed\": false)\n";
    return 128 + signal;
  }
  if (!outcome.stable) {
    std::cerr << "error: simulation unstable: " << outcome.failure << "\n"
              << "results up to the last good step are in " << args.out << "/\n";
    return 3;
  }
  if (!outcome.stopped_on_anomaly.empty()) {
    std::cerr << "error: stopped at the first anomaly: " << outcome.stopped_on_anomaly
              << "\nresults up to that step are in " << args.out << "/\n";
    return 4;
  }
  if (!normal) return 0;
  std::cerr << "done: " << outcome.steps_done << " steps; results in " << args.out
            << "/ (summary.json, wrench.csv, energy.csv, "
            << (s.rigid_bodies.empty() ? "" : "rigid.csv, ") << "one .vtk per body"
            << (s.haptics ? ", haptic_<name>.csv per device" : "") << ")\n";
  return 0;
}

// `torsion run` as its stages; the exit code as reportOutcome documents it.
int run(const RunArguments& args) {
  Result<std::unique_ptr<scene::BuiltScene>> built = loadAndBuild(args);
  if (!built) return fail(built.error().message);
  scene::BuiltScene& s = *built.value();
  describe(args, s);
  Result<std::unique_ptr<render::FrameRecorder>> recorder = startRecorder(args, s);
  if (!recorder) return fail(recorder.error().message);
  Result<std::unique_ptr<VtkSeries>> series = startSeries(args, s);
  if (!series) return fail(series.error().message);
  const Ran ran = runWithProgress(args, s, recorder.value().get(), series.value().get());
  return reportOutcome(args, s, ran, recorder.value().get(), series.value().get());
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
