#pragma once
// The scene runner's watch for silent failures (analysis/step_anomalies.h): one monitor per FEM
// body, a warning line on stderr at the first step of each anomaly, and the "anomalies" array of
// summary.json (docs/scene-format.md).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "torsion/analysis/step_anomalies.h"
#include "torsion/bullet/fem_world.h"

namespace torsion::scene {

class SceneAnomalies {
 public:
  explicit SceneAnomalies(const FemWorld& world);

  /// Observes every body after world step `step`; prints a warning per anomaly that starts now
  /// and returns true when any did.
  bool observe(const FemWorld& world, int step);

  /// The first warning printed ("" when none), for the run's stop reason.
  const std::string& firstWarning() const { return first_warning_; }
  /// [{"body", "kind", "first_step", "last_step", "peak"}, ...] in the order they started.
  nlohmann::json json() const;

 private:
  std::vector<std::string> body_names_;
  std::vector<StepAnomalyMonitor> monitors_;
  // Per body: the inverted-tet counter and the model it was made for (a live material edit
  // makes a new model: its counter is made again).
  std::vector<InvertedTetCounter> counters_;
  std::vector<const FemModel*> counted_models_;
  std::string first_warning_;
};

}  // namespace torsion::scene
