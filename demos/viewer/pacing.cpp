#include "pacing.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace torsion::viewer {

PacingDecision paceFrame(const PacingInput& input, const PacingSettings& settings) {
  PacingDecision d;
  const double owed = std::max(0.0, input.lag + std::max(0.0, input.elapsed));
  if (!(input.dt > 0)) return d;
  // Whole steps of the owed time; the relative 1e-9 keeps a sum of frames that lands on a
  // multiple of dt (up to round-off) from waiting one more frame.
  const double wanted_steps = std::floor(owed / input.dt * (1 + 1e-9));
  const int cap = std::max(1, settings.max_steps_per_frame);
  int affordable = cap;
  if (input.step_cost <= 0) {
    affordable = 1;  // nothing measured yet: one step, then its cost says how many fit
  } else {
    const double fit = std::floor(settings.frame_budget / input.step_cost);
    affordable = fit >= cap ? cap : std::max(1, static_cast<int>(fit));
  }
  if (wanted_steps <= affordable) {
    d.steps = static_cast<int>(wanted_steps);
    d.lag = std::max(0.0, owed - d.steps * input.dt);
    return d;
  }
  d.steps = affordable;
  d.behind = true;
  d.real_time_factor = input.elapsed > 0 ? d.steps * input.dt / input.elapsed : 0;
  return d;
}

std::string realTimeNote(double factor) {
  if (factor >= 0.95 && factor <= 1.05) return "REAL TIME";
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.2gx REAL TIME", std::max(0.0, factor));
  return buf;
}

}  // namespace torsion::viewer
