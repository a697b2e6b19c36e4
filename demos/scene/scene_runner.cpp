#include "scene_runner.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "scene_anomalies.h"
#include "scene_haptics.h"
#include "torsion/mesh/mesh_io.h"
#include "torsion/mesh/vtk_format.h"

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

Status writeFinalMesh(const FemBody& body, const Eigen::VectorXd& positions, const fs::path& path) {
  const TetMesh& mesh = body.model().mesh();
  std::vector<Eigen::Vector3d> x(static_cast<size_t>(mesh.nodeCount()));
  MeshField displacement{"displacement", 3, {}};
  displacement.values.reserve(static_cast<size_t>(3 * mesh.nodeCount()));
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    x[static_cast<size_t>(i)] = positions.segment<3>(3 * i);
    const Eigen::Vector3d u =
        x[static_cast<size_t>(i)] - mesh.restPositions()[static_cast<size_t>(i)];
    displacement.values.insert(displacement.values.end(), {u.x(), u.y(), u.z()});
  }
  MeshFields fields;
  fields.node_fields.push_back(std::move(displacement));
  return writeTextFile(path, formatVtk(mesh, x, fields, body.name()));
}

// Per step: each rigid body's centre of mass, orientation quaternion and linear velocity.
void writeRigidRow(std::ofstream& csv, const BuiltScene& scene, int step, double time) {
  csv << step << "," << time;
  for (const SceneRigidBody& r : scene.rigid_bodies) {
    const btTransform& t = r.body->getCenterOfMassTransform();
    const btQuaternion q = t.getRotation();
    const btVector3& v = r.body->getLinearVelocity();
    csv << "," << t.getOrigin().x() << "," << t.getOrigin().y() << "," << t.getOrigin().z() << ","
        << q.x() << "," << q.y() << "," << q.z() << "," << q.w() << "," << v.x() << "," << v.y()
        << "," << v.z();
  }
  csv << "\n";
}

// FEM-rigid contact figures over the run (docs/contact.md), summed over the FEM bodies per step.
struct ContactTotals {
  int steps = 0;
  long active_sum = 0;
  int active_max = 0;
  double normal_impulse = 0;   // N s
  double max_penetration = 0;  // m, measured at the start of a step
  int active_set_iterations_max = 0;
  int unconverged_steps = 0;

  void add(const FemWorld& world) {
    int active = 0;
    bool converged = true;
    for (const auto& body : world.bodies()) {
      const ContactStepStats& s = body->contacts().stats();
      active += s.active;
      normal_impulse += s.normal_impulse;
      max_penetration = std::max(max_penetration, s.max_penetration);
      active_set_iterations_max = std::max(active_set_iterations_max, s.active_set_iterations);
      converged = converged && s.active_set_converged;
    }
    ++steps;
    active_sum += active;
    active_max = std::max(active_max, active);
    if (!converged) ++unconverged_steps;
  }
  nlohmann::json json() const {
    return {{"active_mean", steps > 0 ? double(active_sum) / steps : 0.0},
            {"active_max", active_max},
            {"normal_impulse_total_Ns", normal_impulse},
            {"max_penetration_m", max_penetration},
            {"active_set_iterations_max", active_set_iterations_max},
            {"active_set_unconverged_steps", unconverged_steps}};
  }
};

}  // namespace

Result<RunOutcome> runScene(BuiltScene& scene, const RunOptions& options) {
  const fs::path out(options.output_directory);
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) return Error{out.string() + ": cannot create the output directory: " + ec.message()};

  FemWorld& world = *scene.world;
  const int steps = options.steps > 0 ? options.steps : scene.spec.steps;

  std::ofstream wrench_csv(out / "wrench.csv"), energy_csv(out / "energy.csv");
  if (!wrench_csv || !energy_csv) return Error{out.string() + ": cannot write the CSV files"};
  wrench_csv << "step,time";
  for (const NodeSetHandle& s : scene.node_sets) {
    for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"})
      wrench_csv << "," << s.name << "." << c;
  }
  for (const SceneHand& h : scene.hands) {
    for (const char* c : {"fx", "fy", "fz", "tx", "ty", "tz"})
      wrench_csv << "," << h.spec.name << "." << c;
  }
  wrench_csv << "\n";
  energy_csv << "step,time";
  for (const auto& body : world.bodies())
    energy_csv << "," << body->name() << ".kinetic," << body->name() << ".elastic";
  energy_csv << ",iterations,relative_residual\n";
  wrench_csv.precision(10);
  energy_csv.precision(10);

  // Rigid bodies' poses per step (only when the scene has some).
  std::ofstream rigid_csv;
  if (!scene.rigid_bodies.empty()) {
    rigid_csv.open(out / "rigid.csv");
    if (!rigid_csv) return Error{out.string() + ": cannot write rigid.csv"};
    rigid_csv << "step,time";
    for (const SceneRigidBody& r : scene.rigid_bodies) {
      for (const char* c : {"x", "y", "z", "qx", "qy", "qz", "qw", "vx", "vy", "vz"})
        rigid_csv << "," << r.name << "." << c;
    }
    rigid_csv << "\n";
    rigid_csv.precision(10);
  }
  ContactTotals contact_totals;
  SceneAnomalies anomalies(world);  // inverted tets, energy release, speed bursts

  std::vector<Eigen::VectorXd> last_good;
  for (const auto& body : world.bodies())
    last_good.push_back(body->state().positions);

  RunOutcome outcome;
  std::vector<double> step_ms;
  step_ms.reserve(static_cast<size_t>(steps));
  long iteration_sum = 0;
  int iteration_max = 0;
  const auto run_start = std::chrono::steady_clock::now();
  if (scene.haptics) scene.haptics->prepareRun(steps);
  for (int k = 0; k < steps; ++k) {
    if (scene.haptics) scene.haptics->pace();  // threaded: wall-clock pacing, not step time
    const auto t0 = std::chrono::steady_clock::now();
    Result<WorldStepReport> stepped = stepScene(scene);
    if (!stepped) return Error{scene.spec.file + ": " + stepped.error().message};
    const WorldStepReport& report = stepped.value();
    step_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!report.ok) {
      outcome.stable = false;
      outcome.failure = report.message;
      break;
    }
    outcome.steps_done = k + 1;
    int iterations = 0;
    double residual = 0;
    for (size_t b = 0; b < world.bodies().size(); ++b) {
      last_good[b] = world.bodies()[b]->state().positions;
      const StepReport& r = world.bodies()[b]->lastReport();
      iterations += r.solve.iterations;
      residual = std::max(residual, r.solve.relative_residual);
    }
    iteration_sum += iterations;
    iteration_max = std::max(iteration_max, iterations);

    wrench_csv << report.step << "," << world.time();
    for (const NodeSetHandle& s : scene.node_sets) {
      const Wrench w = s.body->groupWrench(s.group, s.wrench_about);
      wrench_csv << "," << w.force.x() << "," << w.force.y() << "," << w.force.z() << ","
                 << w.torque.x() << "," << w.torque.y() << "," << w.torque.z();
    }
    for (const SceneHand& h : scene.hands) {  // about the hand's origin O; zero when not holding
      const Wrench w = h.hand->wrench();
      wrench_csv << "," << w.force.x() << "," << w.force.y() << "," << w.force.z() << ","
                 << w.torque.x() << "," << w.torque.y() << "," << w.torque.z();
    }
    wrench_csv << "\n";
    energy_csv << report.step << "," << world.time();
    for (const auto& body : world.bodies()) {
      // kinetic at the end of the step; elastic at its start (the stepper's by-product)
      energy_csv << "," << body->lastReport().kinetic_energy << ","
                 << body->lastReport().elastic_energy;
    }
    energy_csv << "," << iterations << "," << residual << "\n";
    if (rigid_csv.is_open()) writeRigidRow(rigid_csv, scene, report.step, world.time());
    contact_totals.add(world);
    if (anomalies.observe(world, report.step) && options.stop_on_anomaly) {
      outcome.stopped_on_anomaly = anomalies.firstWarning();
      break;
    }
    if (options.progress) {
      const double elapsed =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - run_start).count();
      options.progress(k + 1, steps, elapsed > 0 ? (k + 1) / elapsed : 0.0);
    }
  }

  for (size_t b = 0; b < world.bodies().size(); ++b) {
    const FemBody& body = *world.bodies()[b];
    Status written = writeFinalMesh(body, last_good[b], out / (body.name() + ".vtk"));
    if (!written) return written.error();
  }

  nlohmann::json summary;
  summary["scene"] = scene.spec.name;
  summary["scene_file"] = scene.spec.file;
  summary["steps_requested"] = steps;
  summary["steps"] = outcome.steps_done;
  summary["dt"] = world.settings().solver.time_step;
  summary["simulated_time"] = world.time();
  summary["linear_solver"] = toString(world.settings().solver.linear_solver);
  summary["preconditioner"] = toString(world.settings().solver.preconditioner);
  summary["tolerance"] = world.settings().solver.tolerance;
  summary["threads"] = world.settings().solver.threads;
  summary["ms_per_step"] = {{"median", percentile(step_ms, 0.5)},
                            {"p95", percentile(step_ms, 0.95)}};
  summary["solver_iterations"] = {
      {"mean", outcome.steps_done > 0 ? double(iteration_sum) / outcome.steps_done : 0.0},
      {"max", iteration_max}};
  summary["bodies"] = nlohmann::json::array();
  for (const auto& body : world.bodies()) {
    summary["bodies"].push_back({{"name", body->name()},
                                 {"nodes", body->model().nodeCount()},
                                 {"element", toString(body->model().elementKind())},
                                 {"tets", body->model().elementCount()},
                                 {"mass_kg", body->model().totalMass()}});
  }
  summary["node_sets"] = nlohmann::json::array();
  for (const NodeSetHandle& s : scene.node_sets) {
    summary["node_sets"].push_back(
        {{"name", s.name}, {"body", s.body->name()}, {"nodes", s.node_count}});
  }
  summary["hands"] = nlohmann::json::array();
  for (const SceneHand& h : scene.hands) {
    summary["hands"].push_back(
        {{"name", h.spec.name},
         {"body", h.spec.body},
         {"grabbed_nodes", static_cast<int>(h.hand->selection().nodes.size())},
         {"holding_at_end", h.hand->grabbed()}});
  }
  if (scene.haptics) {  // stops the haptic threads, writes haptic_<hand>.csv
    Result<nlohmann::json> haptics = scene.haptics->finish(out.string());
    if (!haptics) return haptics.error();
    summary["haptics"] = std::move(haptics).value();
    summary["haptic_warnings"] = scene.haptics->warnings();
  }
  if (!scene.rigid_bodies.empty() || scene.spec.ground) summary["contacts"] = contact_totals.json();
  summary["anomalies"] = anomalies.json();
  if (options.stop_on_anomaly) summary["stopped_on_anomaly"] = !outcome.stopped_on_anomaly.empty();
  summary["stable"] = outcome.stable;
  if (!outcome.stable) summary["failure"] = outcome.failure;
  std::ofstream(out / "summary.json") << summary.dump(2) << "\n";
  return outcome;
}

}  // namespace torsion::scene
