#pragma once
// Blends each new simulation step into the rendering instead of stepping it (docs/haptics.md,
// "Passivity"). Between steps the loop renders the local model W_sim + K_h (pose - pose_sim);
// when the next step's wrench arrives the model changes at the current pose by
//     jump = model_new(pose) - model_old(pose),
// the body's own motion over the step (its relaxation after the patch moved, its ringing, its
// stiffness damping) that K_h did not predict. Stepping that in at once, a delay late, feeds
// the body's dynamics back to the hand out of phase: on a stiff body the delayed loop gains
// energy in the twist it is held in, and any passivity controller must then keep cutting the
// wrench, which softens what the hand feels. The blend renders
//     W = model(pose) + offset,   offset -= jump at each new step,   offset *= exp(-2 pi f dt)
// each tick: the change since K_h's prediction comes in through a first-order low-pass of
// cutoff f, and the K_h spring about the current pose stays instantaneous. At rest the offset
// decays to zero, so the static wrench is the model's, exactly (a quasi-static twist feels the
// body's stiffness). The blend is not passive by itself: it lags the body's response (without
// delay it can make a lightly damped loop gain energy too), so it is meant to go with the
// passivity controller, which takes back what it generates.

#include "torsion/device/device_types.h"

namespace torsion::device {

class StepBlend {
 public:
  /// Hz, f above; 0: off (offset() is always zero).
  explicit StepBlend(double cutoff_hz = 0) : cutoff_hz_(cutoff_hz) {}

  /// One tick of `dt` s. `jump`: the change of the model at this tick's pose from the previous
  /// step's to the one that just arrived (zero when none arrived this tick).
  void update(const Wrench& jump, double dt);
  /// Forgets the offset (nothing held, a new grab: the rendering starts from the model).
  void reset() { offset_ = Wrench{}; }

  const Wrench& offset() const { return offset_; }  ///< N, N m: what to add to the model
  bool enabled() const { return cutoff_hz_ > 0; }

 private:
  double cutoff_hz_;
  Wrench offset_;
};

}  // namespace torsion::device
