#include "torsion/device/haptic_loop.h"

#include <pthread.h>
#include <sched.h>
#include <time.h>  // NOLINT(modernize-deprecated-headers): POSIX clock_gettime and friends

#include <algorithm>
#include <cmath>
#include <sstream>

#include "torsion/device/file_io.h"
#include "torsion/device/pose_math.h"

namespace torsion::device {

namespace {

constexpr std::uint32_t kButton1 = 1u << 0;  // grab, force on (report section 5.4)
constexpr std::uint32_t kButton2 = 1u << 1;  // release, force off

double monotonicSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Sleeps until the absolute monotonic time `seconds` (no drift from relative sleeps).
void sleepUntil(double seconds) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(std::floor(seconds));
  ts.tv_nsec = static_cast<long>((seconds - std::floor(seconds)) * 1e9);
  if (ts.tv_nsec >= 1000000000L) {
    ts.tv_sec += 1;
    ts.tv_nsec -= 1000000000L;
  }
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

}  // namespace

std::string HapticLoopSettings::validate() const {
  if (!(rate_hz > 0 && rate_hz <= 20000)) return "rate_hz must be in (0, 20000]";
  if (!(damper.linear >= 0) || !(damper.angular >= 0)) return "damper must be non-negative";
  if (!(twist_cutoff_hz > 0)) return "twist_cutoff_hz must be positive";
  if (!(step_blend_hz >= 0 && std::isfinite(step_blend_hz)))
    return "step_blend_hz must be non-negative (Hz)";
  if (realtime_priority < 0 || realtime_priority > 99)
    return "realtime_priority must be in [0, 99]";
  if (std::string bad = passivity.validate(); !bad.empty()) return bad;
  if (std::string bad = reading.validate(); !bad.empty()) return bad;
  return safety.validate();
}

HapticLoop::HapticLoop(HapticDevice& device, const HapticLoopSettings& settings)
    : device_(device),
      settings_(settings),
      limits_(device.limits()),
      safety_(settings.safety, limits_),
      twist_(settings.twist_cutoff_hz),
      passivity_(settings.passivity),
      blend_(settings.step_blend_hz) {
  force_enabled_ = !settings.buttons_switch_force;
  log_.reserve(settings.log_capacity);
}

HapticLoop::~HapticLoop() {
  stop();
}

// The 1 kHz tick's stages in order, kept in one body so that the loop's timing reads top to
// bottom.
// NOLINTNEXTLINE(readability-function-size)
void HapticLoop::tick(double now, double deadline) {
  ++tick_;
  const double dt = have_previous_ ? now - previous_time_ : 1.0 / settings_.rate_hz;

  // 1-2. device and buttons (rising edges only)
  const bool had_accepted = have_accepted_;
  const Pose last_accepted_pose = accepted_.pose;
  const double last_accepted_at = accepted_at_;
  bool accepted = false;
  const DeviceSample sample = takeReading(now, &accepted);
  const std::uint32_t pressed = sample.alive ? sample.buttons & ~previous_buttons_ : 0;
  if (sample.alive) previous_buttons_ = sample.buttons;
  if (pressed & kButton1) {
    ++grab_requests_;
    force_enabled_ = true;
  }
  if (pressed & kButton2) {
    ++release_requests_;
    force_enabled_ = !settings_.buttons_switch_force;
  }
  // The motion since the last accepted reading, over the time it took: the twist estimate and
  // the port's energy book the motion that happened, and a refused tick (no motion known) books
  // none, so the next accepted reading books the whole of it.
  double port_twist[6] = {};
  double port_dt = 0;
  if (accepted) {
    port_dt = had_accepted ? now - last_accepted_at : 0.0;
    if (port_dt > 0) {
      poseDifference(last_accepted_pose, sample.pose, port_twist);
      for (double& v : port_twist)
        v = std::isfinite(v) ? v / port_dt : 0.0;
    }
    twist_.update(sample.pose, now);
  }
  const double* twist = twist_.twist();

  // 3. command for the simulation
  HandCommand command;
  command.tick = tick_;
  command.time = now;
  command.pose = sample.pose;
  command.alive = sample.alive;
  command.buttons = previous_buttons_;
  command.grab_requests = grab_requests_;
  command.release_requests = release_requests_;
  commands_.write(command);

  // 4. newest simulation wrench and the local model around it
  const SimulationWrench previous_step = simulated_;
  const bool fresh = wrenches_.read(simulated_);
  if (fresh) last_fresh_time_ = now;
  const bool published = simulated_.step > 0;
  Wrench desired;
  if (published && simulated_.grabbed) {
    desired = renderLocalModel(simulated_, sample.pose, twist, settings_.damper, &limits_);
    if (blend_.enabled() && predicts(simulated_)) {
      // A new step of the same grab comes in through the blend (step_blend.h); a new grab
      // starts from the model. Only with K_h: it carries the spring about the current pose at
      // once, and the blend takes what it did not predict.
      Wrench jump;
      if (fresh && previous_step.step > 0 && previous_step.grabbed)
        jump = desired + (-1.0) * renderLocalModel(previous_step, sample.pose, twist,
                                                   settings_.damper, &limits_);
      blend_.update(jump, dt);
      desired = desired + blend_.offset();
    } else {
      blend_.reset();
    }
  } else {
    blend_.reset();
  }
  if (!isFinite(desired)) {
    ++stats_.nonfinite;
    desired = Wrench{};
  }
  if (force_enabled_ &&
      (norm(desired.force) > limits_.max_force || norm(desired.torque) > limits_.max_torque)) {
    ++stats_.saturated;
  }

  // 5. safety, then the device
  SafetyInputs inputs;
  inputs.device_alive = sample.alive;
  inputs.simulation_fresh = published && now - last_fresh_time_ <= settings_.safety.stale_after;
  inputs.grabbed = force_enabled_ && simulated_.grabbed;
  const Wrench previous_output = safety_.output();
  Wrench output = safety_.apply(desired, inputs, dt);
  // The passivity controller (passivity.h) takes the generated energy back; only while healthy
  // and holding: a fading output fades alone. Whichever kind acts, its result goes back
  // through the filter, whose rate limit is the last stage before the device.
  // A refused reading observed no motion: the observer waits for the next accepted one, and the
  // controller, which acts on the observed motion, leaves this tick to the filter.
  const bool holding = inputs.grabbed && inputs.device_alive && inputs.simulation_fresh;
  if (accepted || !holding) passivity_.observe(port_twist, port_dt, holding);
  if (holding && accepted) {
    const double step_dt = std::clamp(dt, 0.0, settings_.safety.fade_time);
    const Wrench controlled = passivity_.control(
        previous_output, output, port_twist, dt, settings_.safety.max_force_rate * step_dt,
        settings_.safety.max_torque_rate * step_dt, limits_);
    // The filter's rate limit is the last stage whatever the controller asks for: a correction
    // beyond it is spread over the next ticks (the observer books what was written).
    output = safety_.follow(controlled, dt);
  }
  device_.write(output);
  passivity_.written(output);
  if (passivity_.activeTicks() != stats_.pc_active.load(std::memory_order_relaxed)) {
    stats_.pc_active.store(passivity_.activeTicks(), std::memory_order_relaxed);
    stats_.pc_dissipated.store(passivity_.dissipated(), std::memory_order_relaxed);
  }
  if (passivity_.portEnergy() > stats_.max_port_energy.load(std::memory_order_relaxed))
    stats_.max_port_energy.store(passivity_.portEnergy(), std::memory_order_relaxed);

  // 6. log
  if (settings_.log_capacity > 0) {
    if (log_.size() < settings_.log_capacity) {
      LoopLogRow row;
      row.tick = tick_;
      row.time = now;
      row.period = dt;
      row.lateness = now - deadline;
      row.pose = sample.pose;
      row.buttons = sample.buttons;
      row.alive = sample.alive;
      row.output = output;
      row.simulated = simulated_.wrench;
      row.sim_step = simulated_.step;
      row.wrench_age = published ? now - last_fresh_time_ : 0;
      // The newest information in the wrench: with a prediction, the device pose read this
      // tick (its reading's age); without, the pose the simulation step used.
      if (published) {
        row.information_age = predicts(simulated_) && simulated_.grabbed
                                  ? std::max(0.0, now - sample.time)
                                  : now - simulated_.command_time;
      }
      row.pose_lag_ticks =
          published ? static_cast<std::int64_t>(tick_ - simulated_.command_tick) : -1;
      row.grabbed = inputs.grabbed;
      row.fresh = fresh;
      row.port_energy = passivity_.portEnergy();
      row.pc_alpha = passivity_.alpha();
      log_.push_back(row);
    } else {
      ++stats_.log_dropped;
    }
  }
  have_previous_ = true;
  previous_time_ = now;
  ++stats_.ticks;
}

DeviceSample HapticLoop::takeReading(double now, bool* accepted) {
  const DeviceSample raw = device_.read(now);
  const ReadingCheck& check = settings_.reading;
  // The motion is checked against the last accepted reading only while the device was alive:
  // a device that comes back (or answers for the first time) may be anywhere within reach.
  const bool tracking = have_accepted_ && accepted_.alive;
  *accepted = isPlausiblePose(raw.pose, check) &&
              (!tracking || isPlausibleMotion(accepted_.pose, raw.pose, now - accepted_at_,
                                              1.0 / settings_.rate_hz, check));
  if (*accepted) {
    accepted_ = raw;
    accepted_at_ = now;
    have_accepted_ = true;
    refused_since_ = -1;
    return raw;
  }
  ++stats_.refused;
  if (refused_since_ < 0) refused_since_ = now;
  if (!have_accepted_) return DeviceSample{};  // nothing to hold: dead, at the origin
  DeviceSample held = accepted_;
  held.alive = accepted_.alive && now - refused_since_ <= check.hold_time;
  return held;
}

void HapticLoop::start() {
  if (thread_.joinable()) return;
  stop_requested_ = false;
  thread_ = std::thread([this] { run(); });
}

void HapticLoop::stop() {
  if (!thread_.joinable()) return;
  stop_requested_ = true;
  thread_.join();
  device_.write(Wrench{});
}

void HapticLoop::run() {
  // Real-time priority, when the process may have it (root or CAP_SYS_NICE): the loop then
  // preempts the simulation and other ordinary jobs on its core instead of waiting its turn.
  // It sleeps most of each period, so it cannot starve them.
  if (settings_.realtime_priority > 0) {
    sched_param param{};
    param.sched_priority = settings_.realtime_priority;
    stats_.realtime = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
  }
  const double period = 1.0 / settings_.rate_hz;
  const double origin = monotonicSeconds();
  double deadline = 0;
  while (!stop_requested_.load(std::memory_order_relaxed)) {
    deadline += period;
    sleepUntil(origin + deadline);
    const double now = monotonicSeconds() - origin;
    if (now - deadline >= period) {
      // A whole period lost (the machine was busy): count it and skip the missed deadlines
      // rather than firing a burst of ticks to catch up.
      ++stats_.overruns;
      deadline = std::floor(now / period) * period;
    }
    tick(now, deadline);
  }
}

void HapticLoop::setLogCapacity(std::size_t rows) {
  settings_.log_capacity = rows;
  log_.reserve(rows);
}

bool HapticLoop::writeLog(const std::string& path, std::string* error) const {
  std::ostringstream out;
  out.precision(10);
  out << "tick,time,period_ms,lateness_ms,px,py,pz,qw,qx,qy,qz,buttons,alive,"
         "fx,fy,fz,tx,ty,tz,sim_fx,sim_fy,sim_fz,sim_tx,sim_ty,sim_tz,"
         "sim_step,wrench_age_ms,pose_lag_ticks,grabbed,fresh,port_energy,pc_alpha,"
         "information_age_ms\n";
  for (const LoopLogRow& r : log_) {
    const Pose& p = r.pose;
    const Wrench& w = r.output;
    const Wrench& s = r.simulated;
    out << r.tick << ',' << r.time << ',' << 1e3 * r.period << ',' << 1e3 * r.lateness << ','
        << p.position.x << ',' << p.position.y << ',' << p.position.z << ',' << p.orientation.w
        << ',' << p.orientation.x << ',' << p.orientation.y << ',' << p.orientation.z << ','
        << r.buttons << ',' << r.alive << ',' << w.force.x << ',' << w.force.y << ',' << w.force.z
        << ',' << w.torque.x << ',' << w.torque.y << ',' << w.torque.z << ',' << s.force.x << ','
        << s.force.y << ',' << s.force.z << ',' << s.torque.x << ',' << s.torque.y << ','
        << s.torque.z << ',' << r.sim_step << ',' << 1e3 * r.wrench_age << ',' << r.pose_lag_ticks
        << ',' << r.grabbed << ',' << r.fresh << ',' << r.port_energy << ',' << r.pc_alpha << ','
        << 1e3 * r.information_age << '\n';
  }
  const std::string failure = writeFileAtomically(path, out.str());
  if (error != nullptr) *error = failure;
  return failure.empty();
}

}  // namespace torsion::device
