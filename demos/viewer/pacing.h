#pragma once
// Real-time pacing of `torsion view`: how many steps each frame takes so that simulated time
// follows the wall clock. Several steps per frame when dt is shorter than a frame, none on some
// frames when it is longer; when the steps cannot keep up, as many as the frame's budget allows
// and the rest of the time given up (slow motion, shown on the HUD), never a backlog that would
// freeze the window. A pure function of its inputs, so tests give it exact numbers.

#include <string>

namespace torsion::viewer {

struct PacingSettings {
  /// s of wall time the steps of one frame may take, by their measured cost: a slow step still
  /// leaves the window about 1 / frame_budget frames per second.
  double frame_budget = 1.0 / 30;
  /// The most steps one frame takes, whatever they cost (a backstop for a cost that jumps).
  int max_steps_per_frame = 32;
};

struct PacingInput {
  double dt = 0.01;      ///< s of simulated time per step (the world's current dt)
  double elapsed = 0;    ///< s of wall time since the previous frame
  double step_cost = 0;  ///< s of wall time one step takes, measured; <= 0: not yet (one step)
  double lag = 0;        ///< s of simulated time owed from earlier frames (PacingDecision::lag)
};

struct PacingDecision {
  int steps = 0;  ///< steps to take this frame
  /// s of simulated time still owed after them, < dt, for the next frame's PacingInput::lag; 0
  /// when behind (the time that could not be simulated is given up, not owed).
  double lag = 0;
  /// Simulated s per wall s over this frame: 1 while keeping up, steps * dt / elapsed when behind.
  double real_time_factor = 1;
  bool behind = false;  ///< fewer steps than the wall clock asked for: slow motion
};

/// This frame's steps: the time owed (lag + elapsed) in whole steps of dt, at most
/// frame_budget / step_cost of them (at least one) and at most max_steps_per_frame.
PacingDecision paceFrame(const PacingInput& input, const PacingSettings& settings = {});

/// The HUD's line for a (smoothed) real-time factor: "REAL TIME" within [0.95, 1.05], else the
/// factor to two significant digits, "0.4x REAL TIME" (a passive viewer's script may also run
/// ahead of the clock: "3.2x REAL TIME").
std::string realTimeNote(double factor);

}  // namespace torsion::viewer
