#pragma once
// Watches a body step by step for the signs of a failure the solver itself does not report: a
// body that turns tets inside out, releases stored elastic energy as a burst of motion, or whose
// nodes suddenly move far faster than they just did. The typical case is a bar twisted past its
// kink: without self-contact it unwinds by passing through itself, which stays numerically
// "stable" (finite, converged) while being physically wrong. Detected, not prevented.
//
// Feed one StepObservation per step (observeStep() makes it from the body's state and the
// stepper's StepReport). Each kind of anomaly is recorded as a range of steps; a condition that
// comes back within AnomalyThresholds::merge_gap_steps extends the range instead of opening a
// new one, so one event gives one warning.
//
// Usage:
//   StepAnomalyMonitor monitor;
//   for (int k = 1; ...; ++k) {
//     stepper.step(state, ...);
//     for (AnomalyKind started : monitor.observe(k, observeStep(model, state.positions, report)))
//       warn(...);
//   }
//   monitor.anomalies();  // every range, in the order they started

#include <Eigen/Core>
#include <deque>
#include <vector>

#include "torsion/analysis/deformation_metrics.h"
#include "torsion/fem/fem_model.h"
#include "torsion/solve/implicit_stepper.h"

namespace torsion {

enum class AnomalyKind {
  kInvertedElements,  ///< tets of the body's mesh with det F <= 0 (for tet10: its linear sub-tets)
  kEnergyRelease,     ///< stored elastic energy turned into kinetic energy within a short window
  kSpeedBurst,        ///< the fastest node far faster than that maximum was shortly before
};
/// "inverted_elements", "energy_release", "speed_burst".
const char* toString(AnomalyKind kind);

/// Defaults and why they are what they are: docs/validation-twist.md, "Twisting past the kink".
struct AnomalyThresholds {
  /// Energy release: within the last `energy_window_steps` steps the kinetic energy rose by more
  /// than `energy_release_fraction` of the elastic energy the body had held through the
  /// `energy_window_steps` steps before the window started (its minimum there: energy an impact
  /// stores and gives back within a few steps is not held), to above anything it had in the
  /// preceding `kinetic_history_steps` (a rebound only gives back what an impact took), while
  /// the elastic energy fell below that held energy by at least half the gain (the motion comes
  /// out of the body's own store, not from work done on it) and the gain exceeds `energy_floor`
  /// (round-off on a body at rest).
  int energy_window_steps = 50;
  double energy_release_fraction = 0.1;
  int kinetic_history_steps = 200;
  double energy_floor = 1e-6;  ///< J
  /// Speed burst: the maximum node speed above `speed_burst_factor` times its median over
  /// `speed_history_steps` steps that ended `speed_window_steps` steps ago (a release takes tens
  /// of steps to speed up; a median that includes them would rise with it), that median floored
  /// at `speed_floor` (a body starting from rest is no burst); checked once that much history is
  /// kept.
  int speed_history_steps = 100;
  int speed_window_steps = 50;
  double speed_burst_factor = 10;
  double speed_floor = 0.1;  ///< m/s
  /// A condition back within this many steps of a range's last step extends that range.
  int merge_gap_steps = 10;
};

/// One body after one step.
struct StepObservation {
  int inverted_elements = 0;
  double kinetic_energy = 0;  ///< J, end of the step
  double elastic_energy = 0;  ///< J, start of the step (the stepper's by-product)
  double max_speed = 0;       ///< m/s, end of the step
};

/// The observation of `model`'s body at `positions` (3n) after a step that returned `report`.
StepObservation observeStep(const FemModel& model, const Eigen::VectorXd& positions,
                            const StepReport& report);
/// The same with the inverted tets counted by `counter` (made for `model`'s mesh): for a body
/// observed after every step.
StepObservation observeStep(const InvertedTetCounter& counter, const FemModel& model,
                            const Eigen::VectorXd& positions, const StepReport& report);

/// A range of steps in which one kind of anomaly held.
struct Anomaly {
  AnomalyKind kind = AnomalyKind::kInvertedElements;
  int first_step = 0;
  int last_step = 0;
  /// The worst value in the range: inverted elements (count); energy release (kinetic gain over
  /// the held elastic energy); speed burst (max speed over its earlier median, floored).
  double peak = 0;
};

class StepAnomalyMonitor {
 public:
  explicit StepAnomalyMonitor(const AnomalyThresholds& thresholds = {});

  /// Records step `step`'s observation; returns the kinds whose range starts at this step (one
  /// warning each). Steps must increase.
  std::vector<AnomalyKind> observe(int step, const StepObservation& observation);

  const std::vector<Anomaly>& anomalies() const { return anomalies_; }
  const AnomalyThresholds& thresholds() const { return thresholds_; }

 private:
  /// The gain/elastic ratio of an energy release ending at this step, or 0 when there is none.
  double energyReleaseRatio(const StepObservation& now) const;
  /// max speed over its floored earlier median when that is a burst, else 0.
  double speedBurstRatio(double max_speed) const;
  /// Extends the latest range of `kind` when `step` is within merge_gap_steps of its end, else
  /// opens a new one; true when it opens one.
  bool record(AnomalyKind kind, int step, double value);

  AnomalyThresholds thresholds_;
  std::deque<StepObservation> history_;  ///< the previous steps, newest last
  std::vector<Anomaly> anomalies_;
};

}  // namespace torsion
