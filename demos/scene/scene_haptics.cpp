#include "scene_haptics.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "device_factory.h"
#include "torsion/device/network_device.h"
#include "torsion/device/plugin_device.h"
#include "torsion/device/pose_math.h"

namespace torsion::scene {

namespace {

// A whole run's ticks in memory (the loop does no I/O while it runs); 10 minutes at 1 kHz at
// most (about 130 MB), beyond which rows are dropped and counted.
constexpr double kMaxLogRows = 600000;

bool livesInWallClockTime(DeviceSpec::Kind kind) {
  return kind == DeviceSpec::Kind::kNetwork || kind == DeviceSpec::Kind::kSpaceMouse;
}

// A plug-in is usually hardware (threaded by default) but may be a simulation that can tick on
// the simulated clock, so --haptics lockstep is allowed for it.
bool prefersWallClockTime(DeviceSpec::Kind kind) {
  return livesInWallClockTime(kind) || kind == DeviceSpec::Kind::kPlugin;
}

// The value at rank round(p (n - 1)) of the sorted values (no interpolation: a reported p99 is a
// latency that occurred).
double nearestRankPercentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[static_cast<size_t>(std::lround(p * static_cast<double>(values.size() - 1)))];
}

nlohmann::json spread(const std::vector<double>& values) {
  return {{"p50", nearestRankPercentile(values, 0.5)},
          {"p99", nearestRankPercentile(values, 0.99)},
          {"max", nearestRankPercentile(values, 1.0)}};
}

std::string fileSafe(const std::string& name) {
  std::string out = name;
  for (char& c : out) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  }
  return out;
}

}  // namespace

Result<SceneHaptics::Channel> SceneHaptics::openChannel(const DeviceSpec& spec,
                                                        const std::string& entry,
                                                        double first_rate_hz) const {
  if (mode_ == HapticsMode::kLockstep && livesInWallClockTime(spec.kind)) {
    return Error{entry + ": a " + std::string(toString(spec.kind)) +
                 " device lives in wall-clock time and cannot tick in lockstep: use "
                 "--haptics threaded"};
  }
  if (first_rate_hz > 0 && mode_ == HapticsMode::kLockstep && spec.loop.rate_hz != first_rate_hz)
    return Error{entry + ".rate_hz: in lockstep every device ticks at the same rate"};
  if (std::string bad = spec.loop.validate(); !bad.empty()) return Error{entry + ": " + bad};
  Result<std::unique_ptr<device::HapticDevice>> opened =
      openDevice(spec, mode_ == HapticsMode::kLockstep);
  if (!opened) return Error{entry + ": " + opened.error().message};
  Channel c;
  c.kind = spec.kind;
  c.device = std::move(opened).value();
  c.loop = std::make_unique<device::HapticLoop>(*c.device, spec.loop);
  c.rate_hz = spec.loop.rate_hz;
  return c;
}

Result<std::unique_ptr<SceneHaptics>> SceneHaptics::attach(BuiltScene& scene) {
  std::unique_ptr<SceneHaptics> h(new SceneHaptics());
  h->dt_ = scene.world->settings().solver.time_step;
  bool live = false;
  for (const SceneHand& s : scene.hands)
    live = live || (s.spec.device && prefersWallClockTime(s.spec.device->kind));
  for (const RigidBodySpec& r : scene.spec.rigid_bodies)
    live = live || (r.device && prefersWallClockTime(r.device->kind));
  h->mode_ = scene.spec.haptics_mode;
  if (h->mode_ == HapticsMode::kAuto)
    h->mode_ = live ? HapticsMode::kThreaded : HapticsMode::kLockstep;

  std::vector<haptics::HapticBinding> bindings;
  auto firstRate = [&bindings] { return bindings.empty() ? 0.0 : bindings.front().rate_hz; };
  auto mappingFor = [](const DeviceSpec& spec, const Frame& anchor) {
    haptics::DeviceMapping mapping;
    mapping.anchor = anchor;
    mapping.position_scale = spec.position_scale;
    mapping.force_scale = spec.force_scale;
    mapping.torque_scale = spec.torque_scale;
    return mapping;
  };
  for (size_t i = 0; i < scene.hands.size(); ++i) {
    SceneHand& s = scene.hands[i];
    if (!s.spec.device) continue;
    const DeviceSpec& spec = *s.spec.device;
    const std::string entry = "hands[" + std::to_string(i) + "] '" + s.spec.name + "': device";
    if (Status ok = spec.coupling.validate(); !ok) return Error{entry + ": " + ok.error().message};
    Result<Channel> opened = h->openChannel(spec, entry, firstRate());
    if (!opened) return opened.error();
    Channel c = std::move(opened).value();
    c.name = s.spec.name;
    c.mapping = mappingFor(spec, s.spec.initial);
    c.coupling = std::make_unique<haptics::HandCoupling>(*s.hand, c.mapping, spec.coupling);
    bindings.push_back({c.coupling.get(), c.loop.get(), c.rate_hz});
    h->channels_.push_back(std::move(c));
  }
  for (size_t i = 0; i < scene.spec.rigid_bodies.size() && i < scene.rigid_bodies.size(); ++i) {
    const RigidBodySpec& r = scene.spec.rigid_bodies[i];
    if (!r.device) continue;
    const std::string entry = "rigid_bodies[" + std::to_string(i) + "] '" + r.name + "': device";
    for (const Channel& other : h->channels_) {
      if (fileSafe(other.name) == fileSafe(r.name))
        return Error{entry + ": its log haptic_" + fileSafe(r.name) + ".csv would be hand '" +
                     other.name + "''s too: rename one"};
    }
    Result<Channel> opened = h->openChannel(*r.device, entry, firstRate());
    if (!opened) return opened.error();
    Channel c = std::move(opened).value();
    c.name = r.name;
    c.tool = true;
    c.mapping = mappingFor(*r.device, r.pose);
    const SceneRigidBody& built = scene.rigid_bodies[i];
    if (r.grasper) {
      Result<std::unique_ptr<haptics::GrasperCoupling>> grasper =
          haptics::GrasperCoupling::create(scene.world->femSolver(), *built.body, built.jaws,
                                           c.mapping, r.device->tool, r.grasper->settings);
      if (!grasper) return Error{entry + ": " + grasper.error().message};
      c.coupling = std::move(grasper).value();
    } else {
      Result<std::unique_ptr<haptics::ToolCoupling>> tool = haptics::ToolCoupling::create(
          *built.body, scene.world->femSolver(), c.mapping, r.device->tool);
      if (!tool) return Error{entry + ": " + tool.error().message};
      c.coupling = std::move(tool).value();
    }
    bindings.push_back({c.coupling.get(), c.loop.get(), c.rate_hz});
    h->channels_.push_back(std::move(c));
  }
  h->runtime_ = std::make_unique<haptics::HapticRuntime>(*scene.world, std::move(bindings));
  if (h->mode_ == HapticsMode::kThreaded)
    h->runtime_->setSimulationPriority(scene.spec.simulation_priority);
  h->simulation_priority_ = scene.spec.simulation_priority;
  h->prepareRun(scene.spec.steps);
  return h;
}

SceneHaptics::~SceneHaptics() {
  if (runtime_ && threads_started_ && !finished_) runtime_->stopThreads();
}

void SceneHaptics::prepareRun(int steps) {
  for (Channel& c : channels_) {
    double rows = std::ceil(steps * dt_ * c.rate_hz) + 2;
    if (mode_ == HapticsMode::kThreaded) rows = 1.25 * rows + 5 * c.rate_hz;  // a slow step
    c.loop->setLogCapacity(static_cast<size_t>(std::min(rows, kMaxLogRows)));
  }
}

void SceneHaptics::pace() {
  if (mode_ == HapticsMode::kLockstep) return;
  if (!threads_started_) {
    runtime_->startThreads();
    threads_started_ = true;
    simulation_real_time_ = runtime_->simulationRealtime();
  }
  runtime_->pace();
}

std::vector<std::string> SceneHaptics::warnings() const {
  std::vector<std::string> all = runtime_->warnings();
  if (threads_started_ && simulation_priority_ > 0 && !simulation_real_time_) {
    all.push_back("--sim-priority " + std::to_string(simulation_priority_) +
                  ": real-time priority refused (needs root or CAP_SYS_NICE); the simulation "
                  "ran at its normal priority");
  }
  return all;
}

WorldStepReport SceneHaptics::step() {
  if (mode_ == HapticsMode::kLockstep) return runtime_->stepLockstep();
  pace();
  return runtime_->step();
}

nlohmann::json SceneHaptics::statistics(const Channel& c) const {
  const std::vector<device::LoopLogRow>& log = c.loop->log();
  std::vector<double> period_error, age, information_age, lateness;
  double max_force = 0, max_torque = 0;
  for (size_t k = 0; k < log.size(); ++k) {
    const device::LoopLogRow& r = log[k];
    if (k > 0) period_error.push_back(1e3 * std::abs(r.period - 1.0 / c.rate_hz));
    if (r.sim_step > 0) age.push_back(1e3 * r.wrench_age);
    if (r.sim_step > 0 && r.grabbed) information_age.push_back(1e3 * r.information_age);
    max_force = std::max(max_force, device::norm(r.output.force));
    max_torque = std::max(max_torque, device::norm(r.output.torque));
  }
  const double span = log.size() > 1 ? log.back().time - log.front().time : 0;
  const device::LoopStats& st = c.loop->stats();
  nlohmann::json j = {
      {c.tool ? "tool" : "hand", c.name},
      {"device", c.device->name()},
      {"mode", toString(mode_)},
      {"clock", mode_ == HapticsMode::kLockstep ? "simulated" : "wall"},
      {"log", "haptic_" + fileSafe(c.name) + ".csv"},
      {"rate_hz", c.rate_hz},
      {"achieved_rate_hz", span > 0 ? static_cast<double>(log.size() - 1) / span : 0.0},
      {"ticks", st.ticks.load()},
      {"period_error_ms", spread(period_error)},
      {"wrench_age_ms", spread(age)},
      {"information_age_ms", spread(information_age)},
      {"saturated_ticks", st.saturated.load()},
      {"overruns", st.overruns.load()},
      {"nonfinite", st.nonfinite.load()},
      {"readings_refused", st.refused.load()},
      {"log_dropped", st.log_dropped.load()},
      {"poses_rejected", c.coupling->rejectedPoses()},
      {"simulation_priority",
       {{"asked", simulation_priority_}, {"real_time", simulation_real_time_}}},
      {"passivity",
       {{"controller", c.loop->passivityEnabled()},
        {"max_port_energy_J", st.max_port_energy.load()},
        {"dissipated_J", st.pc_dissipated.load()},
        {"active_ticks", st.pc_active.load()}}},
      {"max_output", {{"force", max_force}, {"torque", max_torque}}},
      {"limits",
       {{"max_force", c.device->limits().max_force},
        {"max_torque", c.device->limits().max_torque}}}};
  if (const auto* net = dynamic_cast<const device::NetworkDevice*>(c.device.get())) {
    const device::PacketStats& p = net->stats();
    j["packets"] = {{"accepted", p.accepted.load()},
                    {"truncated", p.truncated.load()},
                    {"malformed", p.malformed.load()},
                    {"out_of_order", p.out_of_order.load()},
                    {"duplicate", p.duplicate.load()},
                    {"lost", p.lost.load()},
                    {"foreign", p.foreign.load()},
                    {"sent", p.sent.load()},
                    {"unauthenticated", p.unauthenticated.load()},
                    {"replayed", p.replayed.load()},
                    {"old_version", p.old_version.load()},
                    {"authenticated", net->authenticated()}};
  }
  if (const auto* plugin = dynamic_cast<const device::PluginDevice*>(c.device.get())) {
    const device::PluginStats& p = plugin->stats();
    j["plugin"] = {{"rate_hz", plugin->rateHz()},   {"reads", p.reads.load()},
                   {"late", p.late.load()},         {"failed", p.failed.load()},
                   {"rejected", p.rejected.load()}, {"held", p.held.load()},
                   {"dead", p.dead.load()},         {"isolated", plugin->isolated()}};
    // Only when the host ended during the run: how ("killed by signal 11 (SIGSEGV)").
    if (std::string ended = plugin->hostExit(); !ended.empty()) j["plugin"]["host_exit"] = ended;
  }
  return j;
}

Result<nlohmann::json> SceneHaptics::finish(const std::string& directory) {
  if (threads_started_ && !finished_) {
    runtime_->stopThreads();
  } else if (!finished_) {
    for (Channel& c : channels_)
      c.device->write(device::Wrench{});  // lockstep: the loop does not stop, so zero it here
  }
  finished_ = true;
  nlohmann::json hands = nlohmann::json::array();
  for (const Channel& c : channels_) {
    const std::filesystem::path path =
        std::filesystem::path(directory) / ("haptic_" + fileSafe(c.name) + ".csv");
    if (std::string error; !c.loop->writeLog(path.string(), &error)) return Error{error};
    hands.push_back(statistics(c));
  }
  return hands;
}

std::vector<std::string> SceneHaptics::logFileNames() const {
  std::vector<std::string> names;
  for (const Channel& c : channels_)
    names.push_back("haptic_" + fileSafe(c.name) + ".csv");
  return names;
}

std::vector<std::string> SceneHaptics::describe() const {
  std::vector<std::string> lines;
  for (const Channel& c : channels_) {
    lines.push_back(std::string(c.tool ? "tool '" : "hand '") + c.name + "': device " +
                    c.device->name() + ", " + toString(mode_) + " haptic loop at " +
                    std::to_string(static_cast<int>(c.rate_hz)) + " Hz");
  }
  return lines;
}

std::optional<Wrench> SceneHaptics::deviceWrench(const std::string& name) const {
  for (const Channel& c : channels_) {
    if (c.name == name) return c.coupling->worldWrench();
  }
  return std::nullopt;
}

std::vector<std::pair<std::string, Wrench>> SceneHaptics::toolWrenches() const {
  std::vector<std::pair<std::string, Wrench>> wrenches;
  for (const Channel& c : channels_) {
    if (c.tool) wrenches.emplace_back(c.name, c.coupling->worldWrench());
  }
  return wrenches;
}

std::vector<SceneHaptics::ToolState> SceneHaptics::tools() const {
  std::vector<ToolState> tools;
  for (const Channel& c : channels_) {
    if (!c.tool) continue;
    ToolState t;
    t.name = c.name;
    t.kind = c.kind;
    if (const auto* g = dynamic_cast<const haptics::GrasperCoupling*>(c.coupling.get())) {
      t.goal = g->palm().goal();
      t.jaw_gap = g->gap();
    } else if (const auto* tool = dynamic_cast<const haptics::ToolCoupling*>(c.coupling.get())) {
      t.goal = tool->goal();
    }
    tools.push_back(t);
  }
  return tools;
}

std::optional<SceneHaptics::ManualTool> SceneHaptics::manualTool() const {
  for (const Channel& c : channels_) {
    auto* manual = dynamic_cast<device::ManualDevice*>(c.device.get());
    if (!c.tool || !manual) continue;
    ManualTool m;
    m.name = c.name;
    m.device = manual;
    m.mapping = c.mapping;
    m.grasper = dynamic_cast<const haptics::GrasperCoupling*>(c.coupling.get()) != nullptr;
    return m;
  }
  return std::nullopt;
}

Result<WorldStepReport> stepScene(BuiltScene& scene) {
  Status driven = driveHands(scene);
  if (!driven) return driven.error();
  return scene.haptics ? scene.haptics->step() : scene.world->step();
}

}  // namespace torsion::scene
