#include "scene_runner.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "body_vtk.h"
#include "run_directory.h"
#include "run_provenance.h"
#include "scene_anomalies.h"
#include "scene_haptics.h"
#include "torsion/bullet/rigid_health.h"
#include "torsion/mesh/mesh_io.h"
#include "torsion/mesh/vtk_format.h"
#include "torsion/solve/system_operator.h"

namespace torsion::scene {

namespace fs = std::filesystem;

namespace {

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const double rank = p * static_cast<double>(values.size() - 1);
  const size_t lo = static_cast<size_t>(rank);
  const size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (rank - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

// CSV values as a stream with precision(10) writes them ("%.10g"; std::to_chars with a precision
// is printf's %.*g in the C locale), without a stream per row.
void appendValue(std::string& row, double value) {
  char text[40];
  const std::to_chars_result r =
      std::to_chars(text, text + sizeof text, value, std::chars_format::general, 10);
  row.push_back(',');
  row.append(text, r.ptr);
}

void appendValue(std::string& row, long value) {
  char text[24];
  const std::to_chars_result r = std::to_chars(text, text + sizeof text, value);
  row.push_back(',');
  row.append(text, r.ptr);
}

// "step,time": the start of every row.
void startRow(std::string& row, int step, double time) {
  row.clear();
  appendValue(row, static_cast<long>(step));
  row.erase(0, 1);  // no comma before the first value
  appendValue(row, time);
}

void appendWrench(std::string& row, const Wrench& w) {
  for (double value :
       {w.force.x(), w.force.y(), w.force.z(), w.torque.x(), w.torque.y(), w.torque.z()})
    appendValue(row, value);
}

// Per step: each rigid body's centre of mass, orientation quaternion and linear velocity.
void rigidRow(const BuiltScene& scene, int step, double time, std::string& row) {
  startRow(row, step, time);
  for (const SceneRigidBody& r : scene.rigid_bodies) {
    const btTransform& t = r.body->getCenterOfMassTransform();
    const btQuaternion q = t.getRotation();
    const btVector3& v = r.body->getLinearVelocity();
    for (btScalar value : {t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z(), q.x(), q.y(),
                           q.z(), q.w(), v.x(), v.y(), v.z()})
      appendValue(row, static_cast<double>(value));
  }
  row.push_back('\n');
}

// FEM-rigid contact figures over the run (docs/contact.md), summed over the FEM bodies per step.
struct ContactTotals {
  int steps = 0;
  long active_sum = 0;
  int active_max = 0;
  double normal_impulse = 0;   // N s
  double max_penetration = 0;  // m, measured at the start of a step
  int newton_iterations_max = 0;
  int unconverged_steps = 0;

  void add(const FemWorld& world) {
    int active = 0;
    int rigid_rows = 0;
    bool converged = true;
    for (const auto& body : world.bodies()) {
      if (const SelfContactSolver* self = body->selfContact()) {
        const SelfContactStats& s = self->stats();
        self_active_max = std::max(self_active_max, s.active);
        self_iterations_max = std::max(self_iterations_max, s.iterations);
        self_end_penetration = std::max(self_end_penetration, s.max_end_penetration);
        if (!s.converged) ++self_unconverged_steps;
        has_self_contact = true;
      }
      const ContactStepStats& s = body->contacts().stats();
      active += s.active;
      normal_impulse += s.normal_impulse;
      max_penetration = std::max(max_penetration, s.max_penetration);
      newton_iterations_max = std::max(newton_iterations_max, s.newton_iterations);
      converged = converged && s.converged;
      rigid_rows += s.rigid_rows;
    }
    if (const FemContactIslands* islands = world.femSolver().femContact()) {
      const FemContactStats& s = islands->stats();
      has_fem_contact = true;
      fem_active_sum += s.active;
      fem_active_max = std::max(fem_active_max, s.active);
      fem_candidates_max = std::max(fem_candidates_max, s.candidates);
      fem_iterations_max = std::max(fem_iterations_max, s.iterations);
      fem_normal_impulse += s.normal_impulse;
      fem_end_penetration = std::max(fem_end_penetration, s.max_end_penetration);
      if (!s.converged) ++fem_unconverged_steps;
      if (s.islands > 0) ++fem_contact_steps;
    }
    ++steps;
    active_sum += active;
    active_max = std::max(active_max, active);
    rigid_rows_max = std::max(rigid_rows_max, rigid_rows);
    if (!converged) ++unconverged_steps;
  }
  // The most contacts between rigid bodies the FEM bodies' islands solved in a step.
  int rigid_rows_max = 0;
  // Self-contact (bodies with "self_contact"): summed over bodies, steps counted per body.
  bool has_self_contact = false;
  int self_active_max = 0;
  int self_iterations_max = 0;
  int self_unconverged_steps = 0;
  double self_end_penetration = 0;  // m, linearised, after the solve
  // Contact between FEM bodies (on unless the scene says "fem_contact": false).
  bool has_fem_contact = false;
  long fem_active_sum = 0;
  int fem_active_max = 0, fem_candidates_max = 0, fem_iterations_max = 0;
  int fem_unconverged_steps = 0, fem_contact_steps = 0;
  double fem_normal_impulse = 0;   // N s
  double fem_end_penetration = 0;  // m, linearised, after the solve

  nlohmann::json json() const {
    nlohmann::json j = {{"active_mean", steps > 0 ? double(active_sum) / steps : 0.0},
                        {"active_max", active_max},
                        {"normal_impulse_total_Ns", normal_impulse},
                        {"max_penetration_m", max_penetration},
                        {"newton_iterations_max", newton_iterations_max},
                        {"unconverged_steps", unconverged_steps},
                        {"rigid_rows_max", rigid_rows_max}};
    if (has_self_contact) {
      j["self_contact"] = {{"active_max", self_active_max},
                           {"iterations_max", self_iterations_max},
                           {"unconverged_steps", self_unconverged_steps},
                           {"max_end_penetration_m", self_end_penetration}};
    }
    if (has_fem_contact) {
      j["fem_contact"] = {{"steps_in_contact", fem_contact_steps},
                          {"active_mean", steps > 0 ? double(fem_active_sum) / steps : 0.0},
                          {"active_max", fem_active_max},
                          {"candidates_max", fem_candidates_max},
                          {"normal_impulse_total_Ns", fem_normal_impulse},
                          {"iterations_max", fem_iterations_max},
                          {"unconverged_steps", fem_unconverged_steps},
                          {"max_end_penetration_m", fem_end_penetration}};
    }
    return j;
  }
};

// One run: its outputs, its statistics so far and the summary built from them.
class Run {
 public:
  Run(BuiltScene& scene, const RunOptions& options)
      : scene_(scene),
        world_(*scene.world),
        options_(options),
        steps_(options.steps > 0 ? options.steps : scene.spec.steps),
        anomalies_(world_) {
    for (const SceneRigidBody& r : scene.rigid_bodies)
      rigid_bodies_.push_back({r.name, r.body});
  }

  // The run as its stages: open the outputs, step until done or stopped, write the rest.
  Result<RunOutcome> execute() {
    Result<RunDirectory> dir =
        RunDirectory::prepare(options_.output_directory, outputNames(), summary());
    if (!dir) return dir.error();
    dir_.emplace(std::move(dir).value());
    if (Status opened = openCsvs(); !opened) return fail(opened.error());
    if (Status stepped = stepUntilDoneOrStopped(); !stepped) return fail(stepped.error());
    if (Status finished = writeFinalOutputs(); !finished) return fail(finished.error());
    outcome_.completed = outcome_.stable && outcome_.stopped_by == 0 &&
                         outcome_.stopped_on_anomaly.empty() && outcome_.steps_done == steps_;
    if (Status written = dir_->writeSummary(summary()); !written) return written.error();
    return outcome_;
  }

 private:
  Status stepUntilDoneOrStopped() {
    for (const auto& body : world_.bodies())
      last_good_.push_back(body->state().positions);
    run_start_ = std::chrono::steady_clock::now();
    if (scene_.haptics) scene_.haptics->prepareRun(steps_);
    for (int k = 0; k < steps_; ++k) {
      Result<bool> go_on = runStep(k);
      if (!go_on) return go_on.error();
      if (!go_on.value()) break;
    }
    return Ok{};
  }

  // One step as its stages; false when the run ends with it (unstable, an anomaly, a signal).
  Result<bool> runStep(int k) {
    if (scene_.haptics) scene_.haptics->pace();  // threaded: wall-clock pacing, not step time
    Result<WorldStepReport> stepped = timedStep();
    if (!stepped) return Error{scene_.spec.file + ": " + stepped.error().message};
    const WorldStepReport& report = stepped.value();
    if (!stepWasGood(report)) return false;
    outcome_.steps_done = k + 1;
    if (Status recorded = recordStep(report); !recorded) return recorded.error();
    if (stopsAtAnomaly(report.step)) return false;
    if (Status written = writeStepOutputs(k + 1); !written) return written.error();
    reportProgress(k + 1);
    return !stopWasRequested();
  }

  Result<WorldStepReport> timedStep() {
    const auto t0 = std::chrono::steady_clock::now();
    Result<WorldStepReport> stepped = stepScene(scene_);
    if (stepped) {
      step_ms_.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    }
    return stepped;
  }

  // A step whose solve failed, or after which a rigid body is not finite, ends the run unstable.
  // The solver's report covers both, but it knows a rigid body only by its index in the world:
  // the scene's names are looked up first, so the message names the body as the scene does.
  bool stepWasGood(const WorldStepReport& report) {
    if (auto fault = findUnhealthyRigidBody(rigid_bodies_)) {
      outcome_.stable = false;
      outcome_.failure = "step " + std::to_string(report.step) + ": " + fault->message;
      return false;
    }
    if (!report.ok) {
      outcome_.stable = false;
      outcome_.failure = report.message;
      return false;
    }
    return true;
  }

  // Inverted tets, energy release, speed bursts (scene_anomalies.h): warned, optionally fatal.
  bool stopsAtAnomaly(int step) {
    if (!anomalies_.observe(world_, step) || !options_.stop_on_anomaly) return false;
    outcome_.stopped_on_anomaly = anomalies_.firstWarning();
    return true;
  }

  double stepsPerSecond(int done) const {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start_).count();
    return elapsed > 0 ? done / elapsed : 0.0;
  }

  Status writeStepOutputs(int done) const {
    if (!options_.write_step_outputs) return Ok{};
    return options_.write_step_outputs(done, steps_, stepsPerSecond(done));
  }

  void reportProgress(int done) const {
    if (options_.progress) options_.progress(done, steps_, stepsPerSecond(done));
  }

  bool stopWasRequested() {
    if (!options_.stop_requested) return false;
    outcome_.stopped_by = options_.stop_requested();
    return outcome_.stopped_by != 0;
  }

  std::vector<std::string> outputNames() const {
    std::vector<std::string> names = {"wrench.csv", "energy.csv"};
    if (!scene_.rigid_bodies.empty()) names.push_back("rigid.csv");
    for (const auto& body : world_.bodies())
      names.push_back(body->name() + ".vtk");
    if (scene_.haptics) {
      for (const std::string& log : scene_.haptics->logFileNames())
        names.push_back(log);
    }
    names.insert(names.end(), options_.extra_outputs.begin(), options_.extra_outputs.end());
    return names;
  }

  Status openCsvs() {
    std::string wrench = "step,time";
    for (const NodeSetHandle& s : scene_.node_sets) {
      for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"})
        wrench += "," + s.name + "." + c;
    }
    for (const SceneHand& h : scene_.hands) {
      for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"})
        wrench += "," + h.spec.name + "." + c;
    }
    if (Status s = wrench_csv_.open(dir_->path("wrench.csv"), wrench + "\n"); !s) return s;
    std::string energy = "step,time";
    for (const auto& body : world_.bodies())
      energy += "," + body->name() + ".kinetic," + body->name() + ".elastic";
    if (Status s =
            energy_csv_.open(dir_->path("energy.csv"), energy + ",iterations,relative_residual\n");
        !s)
      return s;
    if (scene_.rigid_bodies.empty()) return Ok{};
    std::string rigid = "step,time";
    for (const SceneRigidBody& r : scene_.rigid_bodies) {
      for (const char* c : {"x", "y", "z", "qx", "qy", "qz", "qw", "vx", "vy", "vz"})
        rigid += "," + r.name + "." + c;
    }
    return rigid_csv_.open(dir_->path("rigid.csv"), rigid + "\n");
  }

  // The rows of one good step, each written whole.
  Status recordStep(const WorldStepReport& report) {
    int iterations = 0;
    double residual = 0;
    for (size_t b = 0; b < world_.bodies().size(); ++b) {
      last_good_[b] = world_.bodies()[b]->state().positions;
      const StepReport& r = world_.bodies()[b]->lastReport();
      iterations += r.solve.iterations;
      residual = std::max(residual, r.solve.relative_residual);
    }
    iteration_sum_ += iterations;
    iteration_max_ = std::max(iteration_max_, iterations);

    // The wrenches of the node sets (their rows of the internal forces only) and of the hands.
    startRow(row_, report.step, world_.time());
    for (const NodeSetHandle& s : scene_.node_sets)
      appendWrench(row_, s.body->groupWrench(s.group, s.wrench_about));
    for (const SceneHand& h : scene_.hands)  // about the hand's origin O; zero when not holding
      appendWrench(row_, h.hand->wrench());
    row_.push_back('\n');
    if (Status s = wrench_csv_.row(row_); !s) return s;

    startRow(row_, report.step, world_.time());
    for (const auto& body : world_.bodies()) {
      // kinetic at the end of the step; elastic at its start (the stepper's by-product)
      appendValue(row_, body->lastReport().kinetic_energy);
      appendValue(row_, body->lastReport().elastic_energy);
    }
    appendValue(row_, static_cast<long>(iterations));
    appendValue(row_, residual);
    row_.push_back('\n');
    if (Status s = energy_csv_.row(row_); !s) return s;
    if (rigid_csv_.isOpen()) {
      rigidRow(scene_, report.step, world_.time(), row_);
      if (Status s = rigid_csv_.row(row_); !s) return s;
    }
    contact_totals_.add(world_);
    return Ok{};
  }

  Status writeFinalOutputs() {
    for (CsvOutput* csv : {&wrench_csv_, &energy_csv_, &rigid_csv_}) {
      if (Status closed = csv->close(); !closed) return closed;
    }
    for (size_t b = 0; b < world_.bodies().size(); ++b) {
      const FemBody& body = *world_.bodies()[b];
      Status written =
          writeTextFile(dir_->path(body.name() + ".vtk"), bodyVtkText(body, last_good_[b]));
      if (!written) return written;
    }
    if (scene_.haptics) {  // stops the haptic threads (zero wrench), writes haptic_<hand>.csv
      Result<nlohmann::json> haptics = scene_.haptics->finish(dir_->directory());
      if (!haptics) return haptics.error();
      haptics_ = std::move(haptics).value();
    }
    return Ok{};
  }

  // Records the error in summary.json when it can still be written, and returns it.
  Error fail(Error error) {
    error_ = error.message;
    if (dir_) {
      if (scene_.haptics) (void)scene_.haptics->finish(dir_->directory());
      (void)dir_->writeSummary(summary());
    }
    return error;
  }

  nlohmann::json summary() const {
    nlohmann::json summary;
    addProvenance(summary);  // schema, version, git commit (run_provenance.h)
    summary["completed"] = outcome_.completed;
    if (outcome_.stopped_by != 0) summary["stopped_by"] = signalName(outcome_.stopped_by);
    if (!error_.empty()) summary["error"] = error_;
    summary["scene"] = scene_.spec.name;
    summary["scene_file"] = scene_.spec.file;
    summary["steps_requested"] = steps_;
    summary["steps"] = outcome_.steps_done;
    summary["dt"] = world_.settings().solver.time_step;
    summary["simulated_time"] = world_.time();
    summary["linear_solver"] = toString(world_.settings().solver.linear_solver);
    summary["preconditioner"] = toString(world_.settings().solver.preconditioner);
    summary["tolerance"] = world_.settings().solver.tolerance;
    summary["threads"] = Parallel::usableThreads(world_.settings().solver.threads);  // used
    // The system operator's kernel build that ran: "avx2+fma" or "sse2" (system_operator.h).
    summary["kernel_path"] = SystemOperator::bestKernelPath();
    summary["ms_per_step"] = {{"median", percentile(step_ms_, 0.5)},
                              {"p95", percentile(step_ms_, 0.95)}};
    summary["solver_iterations"] = {
        {"mean", outcome_.steps_done > 0 ? double(iteration_sum_) / outcome_.steps_done : 0.0},
        {"max", iteration_max_}};
    summary["bodies"] = nlohmann::json::array();
    for (const auto& body : world_.bodies()) {
      summary["bodies"].push_back({{"name", body->name()},
                                   {"nodes", body->model().nodeCount()},
                                   {"element", toString(body->model().elementKind())},
                                   {"tets", body->model().elementCount()},
                                   {"renumbered", !body->inputNumbering().identity()},
                                   {"mass_kg", body->model().totalMass()}});
    }
    summary["node_sets"] = nlohmann::json::array();
    for (const NodeSetHandle& s : scene_.node_sets) {
      summary["node_sets"].push_back(
          {{"name", s.name}, {"body", s.body->name()}, {"nodes", s.node_count}});
    }
    summary["hands"] = nlohmann::json::array();
    for (const SceneHand& h : scene_.hands) {
      summary["hands"].push_back(
          {{"name", h.spec.name},
           {"body", h.spec.body},
           {"grabbed_nodes", static_cast<int>(h.hand->selection().nodes.size())},
           {"holding_at_end", h.hand->grabbed()}});
    }
    if (scene_.haptics) {
      summary["haptics"] = haptics_.is_null() ? nlohmann::json::array() : haptics_;
      summary["haptic_warnings"] = scene_.haptics->warnings();
    }
    if (!scene_.rigid_bodies.empty() || scene_.spec.ground ||
        (scene_.spec.bodies.size() > 1 && scene_.spec.fem_contact))
      summary["contacts"] = contact_totals_.json();
    summary["anomalies"] = anomalies_.json();
    if (options_.stop_on_anomaly)
      summary["stopped_on_anomaly"] = !outcome_.stopped_on_anomaly.empty();
    summary["stable"] = outcome_.stable;
    if (!outcome_.stable) summary["failure"] = outcome_.failure;
    summary["outputs"] = outputNames();
    if (!last_good_.empty()) summary["final_state_hash"] = finalStateHash(scene_, last_good_);
    return summary;
  }

  BuiltScene& scene_;
  FemWorld& world_;
  const RunOptions& options_;
  const int steps_;
  std::vector<NamedRigidBody> rigid_bodies_;
  std::optional<RunDirectory> dir_;
  CsvOutput wrench_csv_, energy_csv_, rigid_csv_;
  std::string row_;  // the CSV row being formatted (its capacity kept across steps)
  std::vector<Eigen::VectorXd> last_good_;
  RunOutcome outcome_;
  std::chrono::steady_clock::time_point run_start_;
  std::vector<double> step_ms_;  // grows with the steps done, never reserved for the requested
  long iteration_sum_ = 0;
  int iteration_max_ = 0;
  ContactTotals contact_totals_;
  SceneAnomalies anomalies_;  // after world_: built from it
  nlohmann::json haptics_;
  std::string error_;
};

}  // namespace

const char* signalName(int signal) {
  switch (signal) {
    case SIGINT:
      return "SIGINT";
    case SIGTERM:
      return "SIGTERM";
    case SIGHUP:
      return "SIGHUP";
    default:
      return "signal";
  }
}

Result<RunOutcome> runScene(BuiltScene& scene, const RunOptions& options) {
  return Run(scene, options).execute();
}

}  // namespace torsion::scene
