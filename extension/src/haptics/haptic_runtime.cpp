#include "torsion/haptics/haptic_runtime.h"

#include <pthread.h>
#include <sched.h>

#include <cassert>
#include <chrono>
#include <cmath>
#include <thread>
#include <utility>

namespace torsion::haptics {

HapticRuntime::HapticRuntime(FemSoftBodySolver& fem, std::vector<HapticBinding> bindings)
    : fem_(fem), bindings_(std::move(bindings)) {
  fem_.addStepListener(this);
}

HapticRuntime::HapticRuntime(FemWorld& world, std::vector<HapticBinding> bindings)
    : HapticRuntime(world.femSolver(), std::move(bindings)) {
  world_ = &world;
}

HapticRuntime::~HapticRuntime() {
  fem_.removeStepListener(this);
}

void HapticRuntime::beforeRigidStep(const StepContext& ctx) {
  if (lockstep_) {
    // Tick k happens at k / rate: count ticks rather than add up periods, so no drift. Bullet
    // hands predictMotion the substep's length rounded to float: its end is known to within a
    // nanosecond.
    constexpr double kEndTolerance = 1e-9;  // s
    const double rate = bindings_.empty() ? 1000 : bindings_.front().rate_hz;
    while (static_cast<double>(lockstep_ticks_) / rate < ctx.endTime() - kEndTolerance) {
      const double now = static_cast<double>(lockstep_ticks_) / rate;
      for (HapticBinding& b : bindings_)
        b.loop->tick(now);
      ++lockstep_ticks_;
    }
  }
  commands_.resize(bindings_.size());
  for (std::size_t i = 0; i < bindings_.size(); ++i) {
    bindings_[i].loop->commands().read(commands_[i]);
    bindings_[i].coupling->beforeRigidStep(commands_[i], ctx);
  }
}

void HapticRuntime::beforeFemStep(const StepContext& ctx) {
  for (std::size_t i = 0; i < bindings_.size() && i < commands_.size(); ++i) {
    const device::HandCommand& command = commands_[i];
    if (command.tick == 0) continue;  // the loop has not ticked yet
    Status applied = bindings_[i].coupling->beforeFemStep(command, ctx);
    if (!applied && warnings_.size() < 100) {
      warnings_.push_back("t = " + std::to_string(ctx.time) +
                          " s: grab failed: " + applied.error().message);
    }
  }
}

void HapticRuntime::afterFemStep(const StepContext& ctx, bool ok) {
  for (HapticBinding& b : bindings_)
    b.coupling->afterFemStep(ctx, ok);
  if (!ok) return;  // a failed step has no wrench to render; the loops fade on their own
  for (HapticBinding& b : bindings_)
    b.loop->wrenches().write(b.coupling->publish(static_cast<std::uint64_t>(ctx.index)));
}

WorldStepReport HapticRuntime::step() {
  assert(world_ != nullptr && "step() needs a HapticRuntime built on a FemWorld");
  return world_->step();
}

WorldStepReport HapticRuntime::stepLockstep() {
  lockstep_ = true;
  return step();
}

void HapticRuntime::startThreads() {
  if (simulation_priority_ > 0 && !simulation_realtime_) {
    sched_param saved{};
    if (pthread_getschedparam(pthread_self(), &saved_policy_, &saved) == 0) {
      saved_priority_ = saved.sched_priority;
      sched_param param{};
      param.sched_priority = simulation_priority_;
      simulation_realtime_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
    }
  }
  for (HapticBinding& b : bindings_)
    b.loop->start();
  // Give the loops a first tick so the first step sees the device.
  for (int wait = 0; wait < 1000; ++wait) {
    bool all = true;
    for (HapticBinding& b : bindings_)
      all = all && b.loop->stats().ticks > 0;
    if (all) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  threads_origin_ = std::chrono::steady_clock::now();
  threads_start_time_ = fem_.time();
}

void HapticRuntime::pace() {
  using Clock = std::chrono::steady_clock;
  const double due = fem_.time() - threads_start_time_;  // the coming step starts at `due`
  std::this_thread::sleep_until(threads_origin_ + std::chrono::duration_cast<Clock::duration>(
                                                      std::chrono::duration<double>(due)));
}

WorldStepReport HapticRuntime::stepPaced(bool real_time) {
  if (real_time) pace();
  return step();
}

void HapticRuntime::stopThreads() {
  for (HapticBinding& b : bindings_)
    b.loop->stop();
  if (simulation_realtime_) {
    sched_param saved{};
    saved.sched_priority = saved_priority_;
    pthread_setschedparam(pthread_self(), saved_policy_, &saved);
    simulation_realtime_ = false;
  }
}

WorldStepReport HapticRuntime::runThreaded(
    int steps, bool real_time, const std::function<bool(const WorldStepReport&)>& after_step) {
  startThreads();
  WorldStepReport report;
  for (int k = 0; k < steps; ++k) {
    report = stepPaced(real_time);
    if (!report.ok) break;
    if (after_step && !after_step(report)) break;
  }
  stopThreads();
  return report;
}

}  // namespace torsion::haptics
