// bench_twist: runs ONE configuration of the cylinder-twist benchmark (twist_protocol.h) and
// prints one JSON line with its metrics. One process per configuration, so the peak RSS it
// reports (getrusage ru_maxrss) belongs to that configuration alone. run_twist_benchmark.sh runs
// the whole matrix, interleaved and repeated.
//
//   bench_twist --solver torsion-cg --mesh cylinder_8332 --E 1e5 --threads 2 --tolerance 1e-4
//   bench_twist --solver bullet-implicit --mesh cylinder_8332 --tolerance 1e-8
//   --mass-preconditioner bench_twist --solver bullet-explicit --mesh cylinder_8332 --substeps 4
//   bench_twist --solver torsion-cg --law neo_hookean --mesh cylinder_8332 --curve nh.csv
//   bench_twist --solver bullet-implicit --law neo_hookean --mesh cylinder_8332 --newton 2

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>

#include "torsion/mesh/mesh_io.h"
#include "torsion/mesh/node_ordering.h"
#include "twist_protocol.h"

#ifndef TORSION_ASSETS_DIR
#define TORSION_ASSETS_DIR "assets/meshes"
#endif

namespace {

using torsion::bench::TwistProtocol;
using torsion::bench::TwistResult;

// NaN and inf are not JSON: write them as null.
nlohmann::json number(double value) {
  if (std::isfinite(value)) return value;
  return nullptr;
}

std::filesystem::path resolveMesh(const std::string& name) {
  std::filesystem::path path(name);
  auto exists = [](const std::filesystem::path& p) {
    return std::filesystem::exists(p) ||
           std::filesystem::exists(std::filesystem::path(p).concat(".node"));
  };
  if (exists(path)) return path;
  const std::filesystem::path in_assets = std::filesystem::path(TORSION_ASSETS_DIR) / name;
  if (exists(in_assets)) return in_assets;
  return path;  // readMesh reports the error
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Cylinder twist benchmark: one configuration, one JSON line on stdout"};
  std::string solver = "torsion-cg";
  std::string mesh_name;
  std::string label;
  std::string dump_path;
  std::string curve_path;
  std::string law = "corotated";
  int bullet_newton = 1;
  TwistProtocol protocol;
  int threads = 1;
  double tolerance = std::numeric_limits<double>::quiet_NaN();
  int substeps = 1;
  int max_iterations = 300;
  bool mass_preconditioner = false;
  std::string element = "tet4";
  std::string preconditioner = "block_jacobi";
  torsion::bench::TorsionOptions torsion_options;
  app.add_option("--solver", solver,
                 "torsion-cg | torsion-cholmod | bullet-implicit | bullet-explicit")
      ->check(
          CLI::IsMember({"torsion-cg", "torsion-cholmod", "bullet-implicit", "bullet-explicit"}));
  app.add_option("--mesh", mesh_name,
                 "mesh file (.node/.ele base name, .msh, .vtk) or a name in assets/meshes")
      ->required();
  app.add_option("--E", protocol.youngs_modulus, "Young's modulus, Pa")->capture_default_str();
  app.add_option("--nu", protocol.poisson_ratio, "Poisson ratio")->capture_default_str();
  app.add_option("--rho", protocol.density, "density, kg/m^3")->capture_default_str();
  app.add_option("--dt", protocol.time_step, "time step, s")->capture_default_str();
  app.add_option("--steps", protocol.total_steps, "total steps (ramp + hold)")
      ->capture_default_str();
  app.add_option("--ramp-steps", protocol.ramp_steps, "steps to reach pi/2")->capture_default_str();
  app.add_option("--beta", protocol.stiffness_damping,
                 "stiffness damping, s (ours and Bullet implicit; explicit corotated has none)")
      ->capture_default_str();
  app.add_option("--max-speed", protocol.max_speed, "m/s; a faster node ends the run as unstable")
      ->capture_default_str();
  app.add_option("--slice-half", protocol.slice_half_thickness,
                 "half thickness of measuring slices, m")
      ->capture_default_str();
  app.add_option("--threads", threads, "worker threads (ours; Bullet is single-threaded)")
      ->capture_default_str();
  app.add_option("--tolerance", tolerance,
                 "ours: CG relative residual (default 1e-4); bullet-implicit: btConjugateGradient "
                 "tolerance, r.z < tol * min(1, z0.b0) (default SIMD_EPSILON)");
  app.add_option("--max-iterations", max_iterations, "Bullet CG iteration cap")
      ->capture_default_str();
  app.add_flag("--mass-preconditioner", mass_preconditioner,
               "bullet-implicit: initialise Bullet's mass preconditioner after the first step");
  app.add_option("--substeps", substeps, "bullet-explicit: stepSimulation calls per dt")
      ->capture_default_str();
  app.add_option("--element", element, "ours: tet4 | tet10 (Bullet always runs the linear tets)")
      ->check(CLI::IsMember({"tet4", "tet10"}));
  app.add_option("--preconditioner", preconditioner, "ours, CG: its preconditioner")
      ->check(CLI::IsMember(
          {"jacobi", "block_jacobi", "lagged_cholesky", "incomplete_cholesky", "two_level"}));
  app.add_option("--refactor-interval", torsion_options.refactor_interval,
                 "ours, lagged preconditioners: refactorise after this many solves")
      ->capture_default_str();
  app.add_option("--refactor-iterations", torsion_options.refactor_iterations,
                 "ours, lagged preconditioners: refactorise after a solve above this many "
                 "iterations")
      ->capture_default_str();
  app.add_option("--oscillate-hz", protocol.oscillation_hz,
                 "> 0: the driven end oscillates at this frequency, amplitude --amplitude")
      ->capture_default_str();
  app.add_option("--amplitude", protocol.final_angle,
                 "rad: the final twist angle, or the oscillation's amplitude")
      ->capture_default_str();
  app.add_option("--law", law,
                 "corotated (ours corotated; Bullet linear-elasticity implicit, corotated "
                 "explicit) | neo_hookean (our stable neo-Hookean, Newton step; Bullet "
                 "btDeformableNeoHookeanForce)")
      ->check(CLI::IsMember({"corotated", "neo_hookean"}))
      ->capture_default_str();
  app.add_option("--newton", bullet_newton,
                 "bullet-implicit: Newton iterations per step (m_maxNewtonIterations; Bullet's "
                 "default 1; always all taken here)")
      ->capture_default_str();
  app.add_option("--newton-tolerance", torsion_options.newton_tolerance,
                 "ours, neo_hookean: SolverSettings::newton_tolerance")
      ->capture_default_str();
  app.add_option("--curve", curve_path,
                 "write step,time,angle,torque per step (torque about z the driver applies at "
                 "the turned end, N m), measured outside the timing");
  app.add_option("--label", label, "free text copied into the JSON");
  app.add_option("--dump-positions", dump_path, "write final positions (x y z per line) here");
  std::string node_order = "file";
  app.add_option("--node-order", node_order,
                 "file (the mesh file's numbering) | rcm (renumbered by reverse Cuthill-McKee, as "
                 "`torsion mesh` writes new meshes; the twist's node sets are chosen by position)")
      ->check(CLI::IsMember({"file", "rcm"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const std::filesystem::path mesh_path = resolveMesh(mesh_name);
  auto loaded = torsion::readMesh(mesh_path);
  if (!loaded.ok()) {
    std::cerr << "bench_twist: " << loaded.error().message << "\n";
    return 2;
  }
  auto mesh = std::make_shared<const torsion::TetMesh>(
      node_order == "rcm" ? torsion::inCacheFriendlyOrder(loaded.value().mesh)
                          : std::move(loaded.value().mesh));

  protocol.law =
      law == "neo_hookean" ? TwistProtocol::Law::kNeoHookean : TwistProtocol::Law::kCorotated;
  protocol.record_curve = !curve_path.empty();
  TwistResult result;
  double reported_tolerance = tolerance;
  if (solver == "torsion-cg" || solver == "torsion-cholmod") {
    torsion::bench::TorsionOptions options = torsion_options;
    options.tet10 = element == "tet10";
    const std::map<std::string, torsion::PreconditionerKind> kinds = {
        {"jacobi", torsion::PreconditionerKind::kJacobi},
        {"block_jacobi", torsion::PreconditionerKind::kBlockJacobi},
        {"lagged_cholesky", torsion::PreconditionerKind::kLaggedCholesky},
        {"incomplete_cholesky", torsion::PreconditionerKind::kIncompleteCholesky},
        {"two_level", torsion::PreconditionerKind::kTwoLevel}};
    options.preconditioner = kinds.at(preconditioner);
    options.cholmod = solver == "torsion-cholmod";
    if (!std::isnan(tolerance)) options.tolerance = tolerance;
    options.threads = threads;
    reported_tolerance =
        options.cholmod ? std::numeric_limits<double>::quiet_NaN() : options.tolerance;
    result = torsion::bench::runTorsionTwist(protocol, mesh, options);
  } else {
    torsion::bench::BulletOptions options;
    options.implicit = solver == "bullet-implicit";
    options.cg_tolerance = std::isnan(tolerance) ? -1 : tolerance;
    options.cg_max_iterations = max_iterations;
    options.mass_preconditioner = mass_preconditioner;
    options.substeps = substeps;
    options.newton_iterations = bullet_newton;
    threads = 1;
    if (!options.implicit) reported_tolerance = std::numeric_limits<double>::quiet_NaN();
    result = torsion::bench::runBulletTwist(protocol, *mesh, options);
  }

  const double total_ms = std::accumulate(result.step_ms.begin(), result.step_ms.end(), 0.0);
  long iterations_total = 0;
  int iterations_max = 0;
  for (int it : result.step_iterations) {
    iterations_total += it;
    iterations_max = std::max(iterations_max, it);
  }
  const double steps_done = std::max(1, result.steps_done);
  long newton_total = 0;
  int newton_max = 0;
  for (int it : result.step_newton) {
    newton_total += it;
    newton_max = std::max(newton_max, it);
  }

  nlohmann::json j;
  j["solver"] = solver;
  j["label"] = label;
  j["detail"] = result.solver_detail;
  j["mesh"] = mesh_path.filename().string();
  j["node_order"] = node_order;
  j["nodes"] = mesh->nodeCount();
  j["tets"] = mesh->tetCount();
  j["element"] = solver.rfind("torsion", 0) == 0 ? element : std::string("tet4");
  j["preconditioner"] = solver == "torsion-cg" ? preconditioner : std::string();
  j["E"] = protocol.youngs_modulus;
  j["nu"] = protocol.poisson_ratio;
  j["rho"] = protocol.density;
  j["dt"] = protocol.time_step;
  j["beta"] = solver == "bullet-explicit" ? 0.0 : protocol.stiffness_damping;
  j["steps"] = protocol.total_steps;
  j["threads"] = threads;
  j["tolerance"] = number(reported_tolerance);
  j["mass_preconditioner"] = solver == "bullet-implicit" && mass_preconditioner;
  j["substeps"] = solver == "bullet-explicit" ? substeps : 1;
  j["status"] = torsion::bench::toString(result.status);
  j["message"] = result.message;
  j["stable"] =
      result.status == torsion::bench::RunStatus::kOk && result.steps_done == protocol.total_steps;
  j["steps_done"] = result.steps_done;
  j["setup_s"] = result.setup_seconds;
  j["run_s"] = total_ms / 1000;
  j["steps_per_s"] = total_ms > 0 ? result.steps_done / (total_ms / 1000) : 0.0;
  j["cpu_ms_per_step"] = 1000 * result.loop_cpu_seconds / steps_done;
  j["ms_median"] = number(torsion::bench::quantile(result.step_ms, 0.5));
  j["ms_p95"] = number(torsion::bench::quantile(result.step_ms, 0.95));
  j["ms_mean"] = total_ms / steps_done;
  j["ms_max"] = number(torsion::bench::quantile(result.step_ms, 1.0));
  j["iterations_total"] = iterations_total;
  j["iterations_mean"] = static_cast<double>(iterations_total) / steps_done;
  j["iterations_max"] = iterations_max;
  j["not_converged_steps"] = result.not_converged_steps;
  j["law"] = law;
  // Newton: ours with the neo-Hookean law; Bullet implicit (its fixed count). iterations_* above
  // are then the CG iterations of all Newton solves together.
  if (!result.step_newton.empty()) {
    j["newton_total"] = newton_total;
    j["newton_mean"] = static_cast<double>(newton_total) / steps_done;
    j["newton_max"] = newton_max;
  } else {
    j["newton_total"] = nullptr;
    j["newton_mean"] = nullptr;
    j["newton_max"] = nullptr;
  }
  j["newton_not_converged_steps"] = result.newton_not_converged_steps;
  j["line_search_cuts"] = result.line_search_cuts;
  j["projected_iterations"] = result.projected_iterations;
  j["end_torque"] = number(result.end_torque);
  const double end_angle = protocol.angle(result.steps_done * protocol.time_step);
  j["torque_st_venant"] = number(torsion::bench::stVenantTorque(protocol, mesh->boundsMax().x(),
                                                                mesh->boundsMax().z(), end_angle));
  j["peak_rss_mb"] = static_cast<double>(result.peak_rss_kb) / 1024;
  j["setup_rss_mb"] = static_cast<double>(result.setup_rss_kb) / 1024;
  j["max_speed"] = number(result.max_speed);
  j["driven_error"] = number(result.driven_error);
  j["tip_angle"] = number(result.tip_angle);
  nlohmann::json slices = nlohmann::json::array();
  for (size_t s = 0; s < result.slice_z.size(); ++s) {
    slices.push_back({{"z", result.slice_z[s]},
                      {"angle", number(result.slice_angle[s])},
                      {"expected", number(result.slice_expected[s])},
                      {"error", number(result.slice_error[s])},
                      {"nodes", result.slice_nodes[s]}});
  }
  j["slices"] = slices;
  std::cout << j.dump() << std::endl;

  if (!dump_path.empty()) {
    std::ofstream out(dump_path);
    out.precision(17);
    for (Eigen::Index i = 0; i + 2 < result.final_positions.size(); i += 3) {
      out << result.final_positions[i] << ' ' << result.final_positions[i + 1] << ' '
          << result.final_positions[i + 2] << '\n';
    }
  }
  if (!curve_path.empty()) {
    std::ofstream out(curve_path);
    out.precision(10);
    out << "step,time,angle,torque\n";
    for (const TwistResult::CurvePoint& p : result.curve)
      out << p.step << ',' << p.step * protocol.time_step << ',' << p.angle << ',' << p.torque
          << '\n';
  }
  return result.status == torsion::bench::RunStatus::kSetupFailed ? 2 : 0;
}
