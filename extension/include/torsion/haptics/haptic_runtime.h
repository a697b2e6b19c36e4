#pragma once
// Ties the world, the hand couplings and their haptic loops together. Two ways to run:
//   - threaded (interactive): each HapticLoop ticks on its own thread at 1 kHz (start()), and
//     the caller's thread is the simulation thread: runThreaded() steps the world as fast as it
//     can or paced to wall-clock time, handing poses and wrenches through the loops' lock-free
//     buffers;
//   - lockstep (headless, deterministic, for tests and plots): stepLockstep() ticks every loop
//     on a simulated clock for one step's worth of ticks, then steps the world.
//
//   Threads | may touch
//   simulation (caller of step*/runThreaded) | the world, hands, couplings; loops' buffers as
//       reader of commands() and writer of wrenches()
//   haptic loop (HapticLoop::start) | its device; its buffers as the other side
// The haptic thread never touches the world.

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "torsion/bullet/fem_world.h"
#include "torsion/device/haptic_loop.h"
#include "torsion/haptics/hand_coupling.h"

namespace torsion::haptics {

struct HapticBinding {
  HandCoupling* coupling = nullptr;
  device::HapticLoop* loop = nullptr;
  double rate_hz = 1000;  ///< the loop's rate, for lockstep ticking
};

class HapticRuntime {
 public:
  HapticRuntime(FemWorld& world, std::vector<HapticBinding> bindings);

  /// Before FemWorld::step(): newest command of each loop -> its coupling. Grab failures are
  /// collected in warnings() (the user pressed the button over nothing), not fatal.
  void beforeStep();
  /// After FemWorld::step(): each coupling publishes to its loop.
  void afterStep();
  /// beforeStep, world step, afterStep.
  WorldStepReport step();
  /// Ticks every loop on the simulated clock up to the end of the coming step, then step().
  WorldStepReport stepLockstep();

  /// Threaded mode in pieces, for callers that own the stepping loop (the scene runner):
  /// startThreads() starts every loop's thread and waits for its first tick (at most 1 s);
  /// stepPaced() is step(), first waiting until wall-clock time since startThreads() has caught
  /// up with simulated time when `real_time`; stopThreads() stops them (zero wrench written).
  void startThreads();
  WorldStepReport stepPaced(bool real_time);
  /// The wait of stepPaced(true) alone: returns when the coming step is due.
  void pace();
  void stopThreads();

  /// Starts the loops' threads, runs `steps` steps on this thread (paced so that simulated time
  /// never runs ahead of wall-clock time when `real_time`), stops the loops. `after_step` may
  /// stop the run early by returning false. Returns the last step's report.
  WorldStepReport runThreaded(int steps, bool real_time,
                              const std::function<bool(const WorldStepReport&)>& after_step = {});

  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  FemWorld& world_;
  std::vector<HapticBinding> bindings_;
  std::vector<std::string> warnings_;
  double loop_clock_ = 0;  // s, simulated clock of the lockstep mode
  std::chrono::steady_clock::time_point threads_origin_;
  double threads_start_time_ = 0;  // world time at startThreads()
  std::uint64_t lockstep_ticks_ = 0;
};

}  // namespace torsion::haptics
