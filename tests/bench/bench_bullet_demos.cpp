// Bullet's deformable demos side by side (docs/performance-contact.md, "Bullet's deformable
// demos, side by side"): each scene file runs in Torsion (FemWorld, one thread) and in Bullet's
// btDeformableMultiBodyDynamicsWorld (bullet_rigid_mix_runner.cpp: same meshes, node sets, rigid
// bodies with their kinematic scripts, gravity and dt), and both end states face the same checks
// (bench_demo_checks.h: exploded, sank, passed through, the demo's defining outcome).
// One JSON line per engine and scene on stdout.
//
//   bench_bullet_demos SCENE.json... [--steps N] [--tolerance M]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "bench_demo_checks.h"
#include "bullet_rigid_mix_runner.h"
#include "scene_builder.h"
#include "scene_parser.h"
#include "torsion/mesh/mesh_io.h"

namespace {

using namespace torsion;

struct Timed {
  std::vector<double> ms;
  std::string error;
  bench::EndState end;
};

Timed runTorsion(const scene::SceneSpec& spec, int steps) {
  Timed run;
  auto built = scene::buildScene(spec, scene::BuildOptions{1});
  if (!built) {
    run.error = built.error().message;
    return run;
  }
  scene::BuiltScene& s = *built.value();
  for (int k = 0; k < steps; ++k) {
    if (Status driven = scene::driveHands(s); !driven) {
      run.error = driven.error().message;
      break;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const WorldStepReport r = s.world->step();
    run.ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    for (const auto& body : s.world->bodies())
      run.end.max_node_speed = std::max(run.end.max_node_speed, body->lastReport().max_speed);
    if (!r.ok) {
      // A blow-up stops Torsion's step (max_speed); the state it leaves is the last good one.
      run.error = r.message;
      run.end.finite = false;
      break;
    }
  }
  for (const auto& body : s.world->bodies()) {
    std::vector<Eigen::Vector3d> nodes;
    for (int i = 0; i < body->model().nodeCount(); ++i)
      nodes.push_back(body->state().position(i));
    run.end.nodes.push_back(std::move(nodes));
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

nlohmann::json row(const scene::SceneSpec& spec, const std::vector<TetMesh>& rest,
                   const std::string& engine, const Timed& run, double tolerance) {
  double total = 0;
  for (double m : run.ms)
    total += m;
  const bench::Verdict v =
      bench::judge(spec, rest, run.end, static_cast<int>(run.ms.size()), tolerance);
  nlohmann::json j = {{"scene", spec.name},
                      {"engine", engine},
                      {"steps", run.ms.size()},
                      {"steps_per_second", total > 0 ? 1000.0 * double(run.ms.size()) / total : 0},
                      {"max_node_speed", run.end.max_node_speed},
                      {"exploded", v.exploded},
                      {"sank", v.sank},
                      {"passed_through", v.passed_through},
                      {"outcome", v.outcome},
                      {"detail", v.detail}};
  if (!run.error.empty()) j["error"] = run.error;
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> paths;
  int steps = -1;
  double tolerance = 0.05;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
      steps = std::atoi(argv[++a]);
    } else if (std::strcmp(argv[a], "--tolerance") == 0 && a + 1 < argc) {
      tolerance = std::atof(argv[++a]);
    } else {
      paths.emplace_back(argv[a]);
    }
  }
  if (paths.empty()) {
    std::cerr << "usage: bench_bullet_demos SCENE.json... [--steps N] [--tolerance M]\n";
    return 1;
  }
  for (const std::string& path : paths) {
    Result<scene::SceneSpec> loaded = scene::loadScene(path);
    if (!loaded) {
      std::cerr << "error: " << loaded.error().message << "\n";
      return 1;
    }
    scene::SceneSpec& spec = loaded.value();
    spec.world.solver.threads = 1;
    const int n = steps > 0 ? steps : spec.steps;
    std::vector<TetMesh> rest;  // placed as the scene places them, for the inverted-tet count
    for (const scene::BodySpec& b : spec.bodies) {
      Result<LoadedMesh> mesh = readMesh(b.mesh_path);
      if (!mesh) {
        std::cerr << "error: " << mesh.error().message << "\n";
        return 1;
      }
      std::vector<Eigen::Vector3d> placed = mesh.value().mesh.restPositions();
      for (Eigen::Vector3d& p : placed)
        p = b.pose.toWorld(p);
      rest.emplace_back(std::move(placed), mesh.value().mesh.tets());
    }
    std::cout << row(spec, rest, "torsion", runTorsion(spec, n), tolerance).dump() << std::endl;
    const bool tet10 = std::any_of(spec.bodies.begin(), spec.bodies.end(),
                                   [](const auto& b) { return b.element != ElementKind::kTet4; });
    if (!spec.hands.empty() || tet10) {
      // The Bullet runner has linear tets and no hand planes: nothing to compare against.
      std::cout << nlohmann::json{{"scene", spec.name},
                                  {"engine", "bullet"},
                                  {"error", "not run: the scene has hands or tet10 bodies"}}
                       .dump()
                << std::endl;
      continue;
    }
    const bench::MixRun b = bench::runBulletMix(spec, n);
    Timed bullet;
    bullet.ms = b.step_ms;
    if (!b.ok) bullet.error = b.message;
    bullet.end.finite = b.ok;
    bullet.end.max_node_speed = b.max_node_speed;
    bullet.end.nodes = b.final_nodes;
    bullet.end.rigid = b.rigid_final_pose;
    std::cout << row(spec, rest, "bullet", bullet, tolerance).dump() << std::endl;
  }
  return 0;
}
