#include "scene_anomalies.h"

#include <cstdio>
#include <iostream>

namespace torsion::scene {

namespace {

std::string describe(AnomalyKind kind, const Anomaly& a, const StepObservation& o) {
  char text[320];
  switch (kind) {
    case AnomalyKind::kInvertedElements:
      std::snprintf(text, sizeof text, "%d inverted tets (det F <= 0)", o.inverted_elements);
      break;
    case AnomalyKind::kEnergyRelease:
      std::snprintf(
          text, sizeof text,
          "kinetic energy (%.4g J) rose by %.0f%% of the elastic energy held while that fell: "
          "stored energy released (the body snapped: a twist buckling into a kink, or a "
          "contact slipping after it stuck)",
          o.kinetic_energy, 100 * a.peak);
      break;
    case AnomalyKind::kSpeedBurst:
      std::snprintf(text, sizeof text,
                    "max node speed %.4g m/s, %.0fx its median before the last steps", o.max_speed,
                    a.peak);
      break;
  }
  return text;
}

}  // namespace

SceneAnomalies::SceneAnomalies(const FemWorld& world) {
  for (const auto& body : world.bodies()) {
    body_names_.push_back(body->name());
    monitors_.emplace_back();
    counters_.emplace_back(body->model());
    counted_models_.push_back(&body->model());
  }
}

bool SceneAnomalies::observe(const FemWorld& world, int step) {
  bool started = false;
  for (size_t b = 0; b < monitors_.size(); ++b) {
    const FemBody& body = *world.bodies()[b];
    if (counted_models_[b] != &body.model()) {
      counters_[b] = InvertedTetCounter(body.model());
      counted_models_[b] = &body.model();
    }
    const StepObservation o =
        observeStep(counters_[b], body.model(), body.state().positions, body.lastReport());
    for (AnomalyKind kind : monitors_[b].observe(step, o)) {
      const std::string line = "body '" + body_names_[b] + "', step " + std::to_string(step) +
                               ": " + describe(kind, monitors_[b].anomalies().back(), o);
      std::cerr << "\nwarning: " << line << "\n";
      if (first_warning_.empty()) first_warning_ = line;
      started = true;
    }
  }
  return started;
}

nlohmann::json SceneAnomalies::json() const {
  nlohmann::json list = nlohmann::json::array();
  for (size_t b = 0; b < monitors_.size(); ++b) {
    for (const Anomaly& a : monitors_[b].anomalies()) {
      list.push_back({{"body", body_names_[b]},
                      {"kind", toString(a.kind)},
                      {"first_step", a.first_step},
                      {"last_step", a.last_step},
                      {"peak", a.peak}});
    }
  }
  return list;
}

}  // namespace torsion::scene
