// Contact between FEM bodies, side by side (docs/performance-contact.md, "Contact between FEM
// bodies: cost, and Bullet side by side"): each scene runs
//   torsion                 as `torsion run` builds it (FemWorld, one thread), with the cost of
//                           detecting FEM pair contacts per step measured on the side
//   torsion_no_fem_contact  the same scene with "fem_contact" off: what the contact costs
//   bullet                  Bullet's btDeformableMultiBodyDynamicsWorld on the same meshes,
//                           masses, initial velocities, gravity and dt (bullet_rigid_mix_runner:
//                           VF_DD and its soft-soft CCD between the bodies), its detection and
//                           solve times from its own profile zones
// and every run faces the same checks (bench_contact_checks.h: interpenetration at the end and
// over every step, momentum and kinetic energy of free bodies, the scene's outcome; and
// bench_demo_checks.h: exploded, sank). One JSON line per run on stdout.
//
// Torsion's detection cost is replayed, not instrumented in the library: before each step, one
// BodyPairContact per pair whose swept boxes overlap (as Bullet's broadphase would note them)
// runs detect() on the same start-of-step positions and velocities, timed alone (process CPU
// time); the step itself is timed without it.
//
//   bench_fem_contact SCENE.json... [--steps N] [--tolerance M] [--bullet-margin M]
//                     [--bullet-substeps K] [--bullet-ground-box] [--only RUN]... [--per-step]
// --tolerance: interpenetration allowed (default 1 % of the smallest body); --bullet-margin:
// Bullet's soft body margin (default 0.01 m); --bullet-substeps: Bullet steps per scene step;
// --bullet-ground-box: Bullet's ground a big box, as in its demos, instead of the scene's plane;
// --only: just these runs (torsion, torsion_no_fem_contact, bullet), e.g. one per callgrind run;
// --per-step: each step's CPU ms, detection ms (and Torsion's Newton iterations, converged) too.

#include <time.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstring>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "bench_contact_checks.h"
#include "bench_demo_checks.h"
#include "bullet_rigid_mix_runner.h"
#include "scene_builder.h"
#include "scene_parser.h"
#include "torsion/bullet/fem_contact_islands.h"
#include "torsion/bullet/fem_soft_body_solver.h"
#include "torsion/contact/body_pair_contact.h"
#include "torsion/mesh/mesh_io.h"

namespace {

using namespace torsion;

double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

struct Run {
  std::vector<double> wall_ms, cpu_ms, detect_cpu_ms, solve_cpu_ms;
  std::string error;
  bench::EndState end;         // for bench_demo_checks (exploded, sank)
  bench::ContactEnd contact;   // for bench_contact_checks
  int fem_candidates_max = 0;  // Torsion: node-triangle candidates, most in a step
  int fem_iterations_max = 0;  // Torsion: the island's Newton iterations, most in a step
  int fem_unconverged = 0;     // Torsion: steps whose FEM pair contact did not converge
  // Torsion, per step: Newton iterations and whether FEM pair contact converged (--per-step).
  std::vector<int> fem_iterations;
  std::vector<bool> fem_converged;
};

// Tracks the deepest interpenetration over the steps.
void noteStep(bench::ContactEnd& c, const std::vector<TetMesh>& rest, const bench::NodeField& x,
              int step, double tolerance) {
  const bench::Penetration p = bench::interpenetration(rest, x, tolerance);
  if (c.worst_step < 0 || p.deepest > c.worst.deepest) {
    c.worst = p;
    c.worst_step = step;
  }
}

bench::NodeField positionsOf(const FemWorld& world) {
  bench::NodeField x;
  for (const auto& body : world.bodies()) {
    std::vector<Eigen::Vector3d> nodes;
    for (int i = 0; i < body->model().nodeCount(); ++i)
      nodes.push_back(body->state().position(i));
    x.push_back(std::move(nodes));
  }
  return x;
}

// The box a body's nodes sweep this step (x to x + dt v), grown by 5 % of its size.
Eigen::AlignedBox3d sweptBox(const FemBody& body, double dt) {
  Eigen::AlignedBox3d box;
  const FemState& s = body.state();
  for (int i = 0; i < body.model().nodeCount(); ++i) {
    const Eigen::Vector3d x = s.positions.segment<3>(3 * i);
    box.extend(x);
    box.extend(Eigen::Vector3d(x + dt * s.velocities.segment<3>(3 * i)));
  }
  const Eigen::Vector3d grow = 0.05 * box.sizes();
  return {box.min() - grow, box.max() + grow};
}

Run runTorsion(const scene::SceneSpec& spec, int steps, const std::vector<TetMesh>& rest,
               double tolerance) {
  Run run;
  auto built = scene::buildScene(spec, scene::BuildOptions{1});
  if (!built) {
    run.error = built.error().message;
    return run;
  }
  scene::BuiltScene& s = *built.value();
  FemWorld& world = *s.world;
  // Contact off: touching bodies pass through each other (a warning) instead of stopping the run.
  if (!spec.fem_contact) world.femSolver().setUnsupportedContact(UnsupportedContact::kWarn);
  const auto& bodies = world.bodies();
  // The replayed detection: one pair contact per pair of bodies, kept across steps as the world
  // keeps its own (their warm starts carry over).
  std::vector<std::unique_ptr<BodyPairContact>> replicas;
  std::vector<std::pair<size_t, size_t>> pairs;
  if (spec.fem_contact) {
    for (size_t a = 0; a < bodies.size(); ++a)
      for (size_t b = a + 1; b < bodies.size(); ++b) {
        pairs.emplace_back(a, b);
        replicas.push_back(std::make_unique<BodyPairContact>(
            bodies[a]->modelPointer(), bodies[b]->modelPointer(), *spec.fem_contact));
      }
  }
  const double dt = spec.world.solver.time_step;
  for (int k = 0; k < steps; ++k) {
    if (Status driven = scene::driveHands(s); !driven) {
      run.error = driven.error().message;
      break;
    }
    double detect_ms = 0;
    if (!pairs.empty()) {
      const double t0 = processCpuMs();
      for (size_t p = 0; p < pairs.size(); ++p) {
        const FemBody& a = *bodies[pairs[p].first];
        const FemBody& b = *bodies[pairs[p].second];
        if (!sweptBox(a, dt).intersects(sweptBox(b, dt))) continue;
        replicas[p]->detect(a.state().positions, a.state().velocities, b.state().positions,
                            b.state().velocities, dt);
      }
      detect_ms = processCpuMs() - t0;
    }
    run.detect_cpu_ms.push_back(detect_ms);
    const double cpu0 = processCpuMs();
    const auto t0 = std::chrono::steady_clock::now();
    const WorldStepReport r = world.step();
    run.wall_ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    run.cpu_ms.push_back(processCpuMs() - cpu0);
    for (const auto& body : bodies)
      run.end.max_node_speed = std::max(run.end.max_node_speed, body->lastReport().max_speed);
    if (const FemContactIslands* islands = world.femSolver().femContact()) {
      const FemContactStats& stats = islands->stats();
      run.fem_candidates_max = std::max(run.fem_candidates_max, stats.candidates);
      run.fem_iterations_max = std::max(run.fem_iterations_max, stats.iterations);
      if (!stats.converged) ++run.fem_unconverged;
      run.fem_iterations.push_back(stats.iterations);
      run.fem_converged.push_back(stats.converged);
    }
    if (!r.ok) {
      run.error = r.message;
      run.end.finite = false;
      break;
    }
    noteStep(run.contact, rest, positionsOf(world), k, tolerance);
  }
  run.end.nodes = positionsOf(world);
  for (const auto& body : bodies) {
    std::vector<Eigen::Vector3d> v;
    for (int i = 0; i < body->model().nodeCount(); ++i)
      v.emplace_back(body->state().velocities.segment<3>(3 * i));
    run.contact.velocities.push_back(std::move(v));
  }
  for (const scene::SceneRigidBody& r : s.rigid_bodies) {
    const btTransform& t = r.body->getWorldTransform();
    Frame pose;
    pose.origin = {t.getOrigin().x(), t.getOrigin().y(), t.getOrigin().z()};
    const btQuaternion q = t.getRotation();
    pose.rotation = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z());
    run.end.rigid.push_back(pose);
  }
  return run;
}

Run runBullet(const scene::SceneSpec& spec, int steps, const std::vector<TetMesh>& rest,
              double tolerance, bench::MixOptions options) {
  Run run;
  options.after_step = [&](int step, const bench::NodeFrames& x) {
    noteStep(run.contact, rest, x, step, tolerance);
  };
  const bench::MixRun b = bench::runBulletMix(spec, steps, options);
  run.wall_ms = b.step_ms;
  run.cpu_ms = b.step_cpu_ms;
  run.detect_cpu_ms = b.detect_cpu_ms;
  run.solve_cpu_ms = b.solve_cpu_ms;
  if (!b.ok) run.error = b.message;
  run.end.finite = b.ok;
  run.end.max_node_speed = b.max_node_speed;
  run.end.nodes = b.final_nodes;
  run.end.rigid = b.rigid_final_pose;
  run.contact.velocities = b.final_velocities;
  return run;
}

double sum(const std::vector<double>& v) {
  double s = 0;
  for (double x : v)
    s += x;
  return s;
}

// The q-quantile of the step times (q = 0.5: median, 1: the slowest step).
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

nlohmann::json row(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest,
                   const std::vector<std::vector<double>>& masses, const bench::Motion& start,
                   const std::string& engine, Run& run, double tolerance, bool per_step) {
  const double n = static_cast<double>(run.cpu_ms.size());
  run.contact.finite = run.end.finite;
  run.contact.nodes = run.end.nodes;
  if (run.end.finite) run.contact.at_end = bench::interpenetration(rest, run.end.nodes, tolerance);
  const bench::Verdict demo =
      bench::judge(spec, rest, run.end, static_cast<int>(run.cpu_ms.size()), tolerance);
  const bench::ContactVerdict contact =
      bench::judgeContact(spec, rest, masses, start, run.contact, tolerance);
  auto perStep = [&](const std::vector<double>& v) { return v.empty() ? 0.0 : sum(v) / n; };
  nlohmann::json j = {
      {"scene", spec.name},
      {"engine", engine},
      {"steps", run.cpu_ms.size()},
      {"steps_per_cpu_second", sum(run.cpu_ms) > 0 ? 1000.0 * n / sum(run.cpu_ms) : 0},
      {"steps_per_wall_second", sum(run.wall_ms) > 0 ? 1000.0 * n / sum(run.wall_ms) : 0},
      {"cpu_ms_per_step", perStep(run.cpu_ms)},
      {"cpu_ms_median_step", quantile(run.cpu_ms, 0.5)},
      {"cpu_ms_slowest_step", quantile(run.cpu_ms, 1)},
      {"detect_cpu_ms_per_step", perStep(run.detect_cpu_ms)},
      {"max_node_speed", run.end.max_node_speed},
      {"exploded", demo.exploded},
      {"sank", demo.sank},
      {"passed_through", contact.passed_through || demo.passed_through},
      {"momentum", contact.momentum},
      {"energy_gained", contact.energy_gained},
      {"outcome", contact.outcome != "n/a" ? contact.outcome : demo.outcome},
      {"tolerance_m", tolerance},
      {"detail", contact.detail + "; " + demo.detail}};
  if (!run.solve_cpu_ms.empty()) j["solve_cpu_ms_per_step"] = perStep(run.solve_cpu_ms);
  if (engine == "torsion") {
    j["fem_candidates_max"] = run.fem_candidates_max;
    j["fem_iterations_max"] = run.fem_iterations_max;
    j["fem_unconverged_steps"] = run.fem_unconverged;
  }
  if (per_step) {
    // [CPU ms, detection CPU ms, Newton iterations, converged] per step (iterations and converged
    // for Torsion with FEM contact only).
    nlohmann::json steps = nlohmann::json::array();
    for (size_t k = 0; k < run.cpu_ms.size(); ++k) {
      nlohmann::json step = {run.cpu_ms[k],
                             k < run.detect_cpu_ms.size() ? run.detect_cpu_ms[k] : 0};
      if (k < run.fem_iterations.size()) {
        step.push_back(run.fem_iterations[k]);
        step.push_back(run.fem_converged[k]);
      }
      steps.push_back(step);
    }
    j["per_step"] = steps;
  }
  if (!run.error.empty()) j["error"] = run.error;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> paths;
  int steps = -1;
  double tolerance = -1;
  bench::MixOptions bullet_options;
  std::vector<std::string> only;
  bool per_step = false;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--bullet-margin") == 0 && a + 1 < argc) {
      bullet_options.margin = std::atof(argv[++a]);
    } else if (std::strcmp(argv[a], "--bullet-substeps") == 0 && a + 1 < argc) {
      bullet_options.substeps = std::atoi(argv[++a]);
    } else if (std::strcmp(argv[a], "--bullet-ground-box") == 0) {
      bullet_options.ground_as_box = true;
    } else if (std::strcmp(argv[a], "--per-step") == 0) {
      per_step = true;
    } else if (std::strcmp(argv[a], "--only") == 0 && a + 1 < argc) {
      only.emplace_back(argv[++a]);
    } else if (std::strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
      steps = std::atoi(argv[++a]);
    } else if (std::strcmp(argv[a], "--tolerance") == 0 && a + 1 < argc) {
      tolerance = std::atof(argv[++a]);
    } else {
      paths.emplace_back(argv[a]);
    }
  }
  if (paths.empty()) {
    std::cerr << "usage: bench_fem_contact SCENE.json... [--steps N] [--tolerance M]\n";
    return 1;
  }
  auto wanted = [&](const std::string& run) {
    return only.empty() || std::find(only.begin(), only.end(), run) != only.end();
  };
  for (const std::string& path : paths) {
    Result<scene::SceneSpec> loaded = scene::loadScene(path);
    if (!loaded) {
      std::cerr << "error: " << loaded.error().message << "\n";
      return 1;
    }
    scene::SceneSpec& spec = loaded.value();
    spec.world.solver.threads = 1;
    const int n = steps > 0 ? steps : spec.steps;
    std::vector<TetMesh> rest;  // placed as the scene places them
    double smallest = std::numeric_limits<double>::infinity();
    for (const scene::BodySpec& b : spec.bodies) {
      Result<LoadedMesh> mesh = readMesh(b.mesh_path);
      if (!mesh) {
        std::cerr << "error: " << mesh.error().message << "\n";
        return 1;
      }
      std::vector<Eigen::Vector3d> placed = mesh.value().mesh.restPositions();
      Eigen::AlignedBox3d box;
      for (Eigen::Vector3d& p : placed) {
        p = b.pose.toWorld(p);
        box.extend(p);
      }
      smallest = std::min(smallest, box.sizes().maxCoeff());
      rest.emplace_back(std::move(placed), mesh.value().mesh.tets());
    }
    // Default: 1 % of the smallest body (0.04 m on the 4 m cubes, 2 mm on the 0.2 m blocks).
    const double tol = tolerance > 0 ? tolerance : 0.01 * smallest;
    const auto masses = bench::lumpedMasses(spec, rest);
    bench::NodeField x0;
    for (const TetMesh& m : rest)
      x0.push_back(m.restPositions());
    const bench::Motion start =
        bench::motionOf(masses, x0, bench::initialVelocities(spec, rest, masses));

    if (wanted("torsion")) {
      Run torsion = runTorsion(spec, n, rest, tol);
      std::cout << row(spec, rest, masses, start, "torsion", torsion, tol, per_step).dump()
                << std::endl;
    }
    if (wanted("torsion_no_fem_contact") && spec.fem_contact && spec.bodies.size() >= 2) {
      scene::SceneSpec off = spec;
      off.fem_contact.reset();
      Run apart = runTorsion(off, n, rest, tol);
      std::cout
          << row(off, rest, masses, start, "torsion_no_fem_contact", apart, tol, per_step).dump()
          << std::endl;
    }
    const bool tet10 = std::any_of(spec.bodies.begin(), spec.bodies.end(),
                                   [](const auto& b) { return b.element != ElementKind::kTet4; });
    if (!wanted("bullet")) continue;
    if (!spec.hands.empty() || tet10) {
      std::cout << nlohmann::json{{"scene", spec.name},
                                  {"engine", "bullet"},
                                  {"error", "not run: the scene has hands or tet10 bodies"}}
                       .dump()
                << std::endl;
      continue;
    }
    Run bullet = runBullet(spec, n, rest, tol, bullet_options);
    nlohmann::json j = row(spec, rest, masses, start, "bullet", bullet, tol, per_step);
    j["bullet_margin"] = bullet_options.margin;
    j["bullet_substeps"] = bullet_options.substeps;
    j["bullet_ground_box"] = bullet_options.ground_as_box;
    std::cout << j.dump() << std::endl;
  }
  return 0;
}
