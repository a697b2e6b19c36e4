// rigid_mix benchmark (docs/performance-contact.md): steps per second of a scene with FEM bodies
// and rigid bodies, run three ways on one thread:
//   torsion           the scene as it is (contacts on)
//   torsion_no_rigid  the same FEM bodies and node sets, rigid bodies and ground removed
//   bullet            Bullet's btDeformableMultiBodyDynamicsWorld on the same meshes, node sets,
//                     rigid bodies, gravity and dt (bullet_rigid_mix_runner.cpp)
// One JSON line per run on stdout: steps, seconds, steps/s, median and p95 ms per step, the rigid
// bodies' final heights (a sanity check that both worlds held them up) and the fastest node.
//
//   bench_rigid_mix [SCENE.json] [--steps N]

#include <algorithm>
#include <chrono>
#include <cstring>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "bullet_rigid_mix_runner.h"
#include "scene_builder.h"
#include "scene_parser.h"

namespace {

using namespace torsion;

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(p * static_cast<double>(v.size() - 1))];
}

nlohmann::json report(const std::string& name, const std::vector<double>& ms,
                      const std::vector<double>& rigid_z, double fastest, const std::string& note) {
  double total = 0;
  for (double m : ms)
    total += m;
  return {{"run", name},
          {"steps", ms.size()},
          {"seconds", total / 1000},
          {"steps_per_second", ms.empty() ? 0.0 : 1000.0 * static_cast<double>(ms.size()) / total},
          {"ms_median", percentile(ms, 0.5)},
          {"ms_p95", percentile(ms, 0.95)},
          {"rigid_final_z", rigid_z},
          {"fastest_node", fastest},
          {"note", note}};
}

nlohmann::json runTorsion(scene::SceneSpec spec, int steps, bool rigid, const std::string& name) {
  if (!rigid) {
    spec.rigid_bodies.clear();
    spec.ground.reset();
  }
  auto built = scene::buildScene(std::move(spec), scene::BuildOptions{1});
  if (!built) return {{"run", name}, {"error", built.error().message}};
  scene::BuiltScene& s = *built.value();
  std::vector<double> ms;
  double fastest = 0;
  for (int k = 0; k < steps; ++k) {
    if (Status driven = scene::driveHands(s); !driven)
      return {{"run", name}, {"error", driven.error().message}};
    const auto t0 = std::chrono::steady_clock::now();
    const WorldStepReport r = s.world->step();
    ms.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!r.ok) return {{"run", name}, {"error", r.message}};
    for (const auto& body : s.world->bodies())
      fastest = std::max(fastest, body->lastReport().max_speed);
  }
  std::vector<double> z;
  for (const scene::SceneRigidBody& r : s.rigid_bodies)
    z.push_back(r.body->getCenterOfMassPosition().z());
  return report(name, ms, z, fastest, "FemWorld, 1 thread");
}

}  // namespace

int main(int argc, char** argv) {
  std::string path = std::string(TORSION_SCENES_DIR) + "/rigid_mix.json";
  int steps = -1;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
      steps = std::atoi(argv[++a]);
    } else {
      path = argv[a];
    }
  }
  Result<scene::SceneSpec> spec = scene::loadScene(path);
  if (!spec) {
    std::cerr << "error: " << spec.error().message << "\n";
    return 1;
  }
  spec.value().world.solver.threads = 1;
  if (steps < 1) steps = spec.value().steps;
  std::cout << runTorsion(spec.value(), steps, true, "torsion").dump() << "\n";
  std::cout << runTorsion(spec.value(), steps, false, "torsion_no_rigid").dump() << "\n";
  const bench::MixRun b = bench::runBulletMix(spec.value(), steps);
  nlohmann::json j = report("bullet", b.step_ms, b.rigid_final_z, b.max_node_speed, b.detail);
  if (!b.ok) j["error"] = b.message;
  std::cout << j.dump() << "\n";
  return 0;
}
