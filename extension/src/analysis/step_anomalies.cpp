#include "torsion/analysis/step_anomalies.h"

#include <algorithm>
#include <cmath>

#include "torsion/analysis/deformation_metrics.h"

namespace torsion {

const char* toString(AnomalyKind kind) {
  switch (kind) {
    case AnomalyKind::kInvertedElements:
      return "inverted_elements";
    case AnomalyKind::kEnergyRelease:
      return "energy_release";
    case AnomalyKind::kSpeedBurst:
      return "speed_burst";
  }
  return "unknown";
}

StepObservation observeStep(const FemModel& model, const Eigen::VectorXd& positions,
                            const StepReport& report) {
  return observeStep(InvertedTetCounter(model), model, positions, report);
}

StepObservation observeStep(const InvertedTetCounter& counter, const FemModel& model,
                            const Eigen::VectorXd& positions, const StepReport& report) {
  StepObservation o;
  o.inverted_elements = counter.count(model, positions);
  o.kinetic_energy = report.kinetic_energy;
  o.elastic_energy = report.elastic_energy;
  o.max_speed = report.max_speed;
  return o;
}

StepAnomalyMonitor::StepAnomalyMonitor(const AnomalyThresholds& thresholds)
    : thresholds_(thresholds) {}

std::vector<AnomalyKind> StepAnomalyMonitor::observe(int step, const StepObservation& now) {
  std::vector<AnomalyKind> started;
  if (now.inverted_elements > 0 &&
      record(AnomalyKind::kInvertedElements, step, now.inverted_elements))
    started.push_back(AnomalyKind::kInvertedElements);
  if (const double r = energyReleaseRatio(now);
      r > 0 && record(AnomalyKind::kEnergyRelease, step, r))
    started.push_back(AnomalyKind::kEnergyRelease);
  if (const double r = speedBurstRatio(now.max_speed);
      r > 0 && record(AnomalyKind::kSpeedBurst, step, r))
    started.push_back(AnomalyKind::kSpeedBurst);

  history_.push_back(now);
  const size_t keep = static_cast<size_t>(
      std::max(2 * thresholds_.energy_window_steps + thresholds_.kinetic_history_steps,
               thresholds_.speed_history_steps + thresholds_.speed_window_steps));
  while (history_.size() > keep)
    history_.pop_front();
  return started;
}

double StepAnomalyMonitor::energyReleaseRatio(const StepObservation& now) const {
  const int size = static_cast<int>(history_.size());
  const int window = std::min(thresholds_.energy_window_steps, size);
  if (window == 0) return 0;
  const auto at = [this](int i) -> const StepObservation& {
    return history_[static_cast<size_t>(i)];
  };
  // Largest kinetic energy over kinetic_history_steps before the window, then up to each window
  // start j.
  const int first_j = size - window;
  double kinetic_before = 0;
  for (int i = std::max(0, first_j - thresholds_.kinetic_history_steps); i < first_j; ++i)
    kinetic_before = std::max(kinetic_before, at(i).kinetic_energy);
  double best = 0;
  for (int j = first_j; j < size; ++j) {
    kinetic_before = std::max(kinetic_before, at(j).kinetic_energy);
    // The elastic energy held through the window's length before j: what an impact stores and
    // gives back within a few steps is not in it.
    double held = at(j).elastic_energy;
    for (int i = std::max(0, j - thresholds_.energy_window_steps); i < j; ++i)
      held = std::min(held, at(i).elastic_energy);
    const double gain = now.kinetic_energy - kinetic_before;
    const double drop = held - now.elastic_energy;
    if (gain > thresholds_.energy_floor && gain > thresholds_.energy_release_fraction * held &&
        drop >= 0.5 * gain)
      best = std::max(best, gain / held);
  }
  return best;
}

double StepAnomalyMonitor::speedBurstRatio(double max_speed) const {
  const size_t n = static_cast<size_t>(thresholds_.speed_history_steps);
  const size_t lag = static_cast<size_t>(thresholds_.speed_window_steps);
  if (n == 0 || history_.size() < n + lag) return 0;
  std::vector<double> earlier;
  earlier.reserve(n);
  const size_t end = history_.size() - lag;
  for (size_t i = end - n; i < end; ++i)
    earlier.push_back(history_[i].max_speed);
  std::nth_element(earlier.begin(), earlier.begin() + static_cast<long>(n / 2), earlier.end());
  const double reference = std::max(earlier[n / 2], thresholds_.speed_floor);
  const double ratio = max_speed / reference;
  // A non-finite speed is a burst too (the stepper reports it fatally anyway).
  return (ratio > thresholds_.speed_burst_factor || !std::isfinite(ratio)) ? ratio : 0;
}

bool StepAnomalyMonitor::record(AnomalyKind kind, int step, double value) {
  for (auto it = anomalies_.rbegin(); it != anomalies_.rend(); ++it) {
    if (it->kind != kind) continue;
    if (step - it->last_step <= thresholds_.merge_gap_steps) {
      it->last_step = step;
      it->peak = std::max(it->peak, value);
      return false;
    }
    break;
  }
  anomalies_.push_back({kind, step, step, value});
  return true;
}

}  // namespace torsion
