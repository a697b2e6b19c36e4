#pragma once
// Runs a built scene headless and writes its results into a directory:
//   summary.json  steps, dt, ms per step (median, p95), solver iterations (mean, max), node and
//                 tet counts per body, stable or the failure, the anomalies seen
//                 (scene_anomalies.h)
//   wrench.csv    per step, per node set: force and torque the body exerts on the set, about the
//                 set's wrench_about point
//   energy.csv    per step, per body: kinetic and elastic energy
//   <body>.vtk    final mesh of each body with its displacement (last good state on failure)
//   rigid.csv     per step, per rigid body: pose and velocity (scenes with rigid bodies)
//   haptic_<name>.csv  the haptic loop's log per device (hand or tool)
// How the directory is kept consistent across runs and stops (completed, error, signal, kill):
// run_directory.h and docs/outputs.md.

#include <functional>
#include <string>
#include <vector>

#include "scene_builder.h"

namespace torsion::scene {

struct RunOptions {
  std::string output_directory = "results";
  int steps = -1;  ///< < 0: the scene's own
  /// Called after every step with (step, total, steps per second so far).
  std::function<void(int, int, double)> progress;
  /// Called after every step, before `progress`, with the same values: writes the caller's own
  /// outputs of the step (a ParaView series, pictures). An error is an output that could not be
  /// written: the run stops there, summary.json says "completed": false with the error, and
  /// runScene returns it.
  std::function<Status(int, int, double)> write_step_outputs;
  /// Stop after the step in which the first anomaly (scene_anomalies.h) starts.
  bool stop_on_anomaly = false;
  /// Polled after every step: a signal number (SIGINT, SIGTERM) stops the run there, with every
  /// output written for the steps done; 0 goes on.
  std::function<int()> stop_requested;
  /// Files the caller writes into the directory besides the runner's own (e.g. "series.pvd"):
  /// listed in summary.json's "outputs", so the next run there removes them (run_directory.h).
  std::vector<std::string> extra_outputs;
};

/// The name of a signal that stops a run ("SIGINT", "SIGTERM", "SIGHUP"), as summary.json's
/// "stopped_by" says it.
const char* signalName(int signal);

struct RunOutcome {
  bool stable = true;
  std::string failure;  ///< the first fatal report, when not stable
  int steps_done = 0;
  /// With RunOptions::stop_on_anomaly: the anomaly the run stopped at ("" when it did not).
  std::string stopped_on_anomaly;
  int stopped_by = 0;      ///< the signal that stopped the run, 0 if none
  bool completed = false;  ///< every requested step ran and every output was written
};

/// Errors are for output that cannot be written (summary.json then says "completed": false and
/// the error, when it can still be written); an unstable simulation is a RunOutcome.
Result<RunOutcome> runScene(BuiltScene& scene, const RunOptions& options);

}  // namespace torsion::scene
