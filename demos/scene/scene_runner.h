#pragma once
// Runs a built scene headless and writes its results into a directory:
//   summary.json  steps, dt, ms per step (median, p95), solver iterations (mean, max), node and
//                 tet counts per body, stable or the failure, the anomalies seen
//                 (scene_anomalies.h)
//   wrench.csv    per step, per node set: force and torque the body exerts on the set, about the
//                 set's wrench_about point
//   energy.csv    per step, per body: kinetic and elastic energy
//   <body>.vtk    final mesh of each body with its displacement (last good state on failure)

#include <functional>
#include <string>

#include "scene_builder.h"

namespace torsion::scene {

struct RunOptions {
  std::string output_directory = "results";
  int steps = -1;  ///< < 0: the scene's own
  /// Called after every step with (step, total, steps per second so far).
  std::function<void(int, int, double)> progress;
  /// Stop after the step in which the first anomaly (scene_anomalies.h) starts.
  bool stop_on_anomaly = false;
};

struct RunOutcome {
  bool stable = true;
  std::string failure;  ///< the first fatal report, when not stable
  int steps_done = 0;
  /// With RunOptions::stop_on_anomaly: the anomaly the run stopped at ("" when it did not).
  std::string stopped_on_anomaly;
};

/// Errors are for output that cannot be written; an unstable simulation is a RunOutcome.
Result<RunOutcome> runScene(BuiltScene& scene, const RunOptions& options);

}  // namespace torsion::scene
