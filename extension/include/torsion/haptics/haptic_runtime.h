#pragma once
// Ties the FEM solver, the device couplings (hand planes and tools, device_coupling.h) and their
// haptic loops together. It listens to the solver's steps (FemSoftBodySolver::addStepListener),
// so it works in any world the solver is attached to, whoever calls stepSimulation and with
// whatever substeps:
//   before the rigid solve  in lockstep mode, every loop ticked on the simulated clock up to the
//                           substep's end; then each loop's newest command is taken, and handed
//                           to its coupling (a tool acts here);
//   before each FEM step    the same command again (a hand acts here);
//   after each FEM step     each coupling closes the step, and publishes its wrench to its loop.
// Two ways to run:
//   - threaded (interactive): each HapticLoop ticks on its own thread at 1 kHz (startThreads()),
//     and the thread that steps the world is the simulation thread, handing poses and wrenches
//     through the loops' lock-free buffers;
//   - lockstep (headless, deterministic, for tests and plots): setLockstep(true).
// On a FemWorld the runtime can also step the world itself (step, stepLockstep, runThreaded).
//
//   Threads | may touch
//   simulation (the one stepping the world) | the world, hands, couplings; loops' buffers as
//       reader of commands() and writer of wrenches()
//   haptic loop (HapticLoop::start) | its device; its buffers as the other side
// The haptic thread never touches the world.

#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/device/haptic_loop.h"
#include "torsion/haptics/device_coupling.h"

namespace torsion::haptics {

struct HapticBinding {
  DeviceCoupling* coupling = nullptr;
  device::HapticLoop* loop = nullptr;
  double rate_hz = 1000;  ///< the loop's rate, for lockstep ticking
};

class HapticRuntime : public StepListener {
 public:
  /// On a user's own world: the solver (attached to it) tells the runtime of every FEM step.
  HapticRuntime(FemSoftBodySolver& fem, std::vector<HapticBinding> bindings);
  /// On a FemWorld: the same, and step()/stepLockstep()/runThreaded() step the world.
  HapticRuntime(FemWorld& world, std::vector<HapticBinding> bindings);
  ~HapticRuntime() override;
  HapticRuntime(const HapticRuntime&) = delete;
  HapticRuntime& operator=(const HapticRuntime&) = delete;

  /// Lockstep: before each FEM step every loop ticks on the simulated clock, k / rate, up to the
  /// step's end (headless, deterministic). Off: the loops tick on their own threads.
  void setLockstep(bool lockstep) { lockstep_ = lockstep; }

  // ---- StepListener (called by the solver inside stepSimulation) ----
  void beforeRigidStep(const StepContext& ctx) override;
  void beforeFemStep(const StepContext& ctx) override;
  void afterFemStep(const StepContext& ctx, bool ok) override;

  // ---- stepping a FemWorld ----
  /// One world step (the world's own dt).
  WorldStepReport step();
  /// setLockstep(true), then step().
  WorldStepReport stepLockstep();

  /// Threaded mode in pieces, for callers that own the stepping loop (the scene runner, or a
  /// user's stepSimulation loop): startThreads() starts every loop's thread and waits for its
  /// first tick (at most 1 s); stepPaced() is step(), first waiting until wall-clock time since
  /// startThreads() has caught up with simulated time when `real_time`; stopThreads() stops them
  /// (zero wrench written).
  void startThreads();
  /// SCHED_FIFO priority (1-99) the thread that calls startThreads() asks for until
  /// stopThreads(), so that on a loaded machine the steps run at the speed of an idle one and
  /// the wrench the loop renders stays young (docs/performance-haptics.md: wrench age p99 10 ms
  /// at 31558 tets under load 13, against 100 ms without). Keep it below the loops' (80) so that
  /// they still preempt the simulation. The solver's worker threads inherit it when the thread
  /// starts them (their first parallel step). Linux caps real-time threads at 95 % of the CPU
  /// (sched_rt_runtime_us), so a simulation slower than real time cannot lock the machine.
  /// Refused silently without the privilege (simulationRealtime() says). 0 (default): keep the
  /// thread's policy.
  void setSimulationPriority(int priority) { simulation_priority_ = priority; }
  /// The stepping thread runs under SCHED_FIFO (from startThreads() until stopThreads()).
  bool simulationRealtime() const { return simulation_realtime_; }
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
  FemSoftBodySolver& fem_;
  FemWorld* world_ = nullptr;  // set when built on a FemWorld
  std::vector<HapticBinding> bindings_;
  std::vector<device::HandCommand> commands_;  // each loop's newest, taken before the rigid solve
  std::vector<std::string> warnings_;
  bool lockstep_ = false;
  std::chrono::steady_clock::time_point threads_origin_;
  double threads_start_time_ = 0;  // FEM time at startThreads()
  std::uint64_t lockstep_ticks_ = 0;
  int simulation_priority_ = 0;
  bool simulation_realtime_ = false;
  int saved_policy_ = 0;  // the stepping thread's policy before startThreads()
  int saved_priority_ = 0;
};

}  // namespace torsion::haptics
