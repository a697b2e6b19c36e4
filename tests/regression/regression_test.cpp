// Scene regression tests (label "regression"): every scene in demos/scenes/ runs headless for a
// few steps with 1 and with 2 worker threads; its summary metrics must match the values stored in
// tests/data/regression/scene_metrics.json within the tolerances below, and the state hash must
// be the same for both thread counts (the solver is bit-identical for any thread count) and,
// when one is stored for this toolchain, equal to it.
//
// Scenes are found when the tests run, so a new scene needs only its entry. To write or refresh
// entries (one process, so the file is not written concurrently), then review the diff:
//   TORSION_UPDATE_REGRESSION=1 build/tests/regression/torsion_regression_tests

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "scene_builder.h"
#include "scene_haptics.h"
#include "scene_parser.h"
#include "torsion/bt_conversions.h"
#include "torsion/fnv1a.h"
#include "torsion/solve/system_operator.h"

namespace torsion::scene {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Tolerances. The metrics follow from velocities that CG solves to a relative residual of 1e-4
// (the scenes' setting). Another compiler or library rounds differently, CG may then stop an
// iteration earlier or later, and the state moves by a fraction of that residual's effect. An
// upper bound of that effect, measured by solving the twist scenes (2430, 8332; 50 steps) to 1e-6
// instead of 1e-4: energies moved by <= 2.4e-4 relative, the hand's torque by <= 1.4e-4 of its
// magnitude, its force by <= 2e-2 of its magnitude (in a pure twist the force is a small
// residual of balanced node forces, |F| ~ 2 % of |T| / r). So: energies, maximum displacement and
// torques within 2e-3 relative (~10x the bound), forces within 5e-2 of their magnitude. A 1 %
// change of the modulus moves the energies and the torque by ~5e-3 and fails (tested
// below). Components below 1e-3 of the scene's largest force (torque) are round-off and solver
// residue (e.g. the base before the twist reaches it) and are compared with that floor.
// Energies likewise against the scene's energy: the residual is relative to the whole step's
// right-hand side, so it moves an energy by a fraction of the motion's energy, not of its own.
// Where one of the two is small the difference shows: the plectoneme at step 50 twists slowly
// (kinetic energy 1.4 % of the total), and solving it to 1e-6 moved its kinetic energy by 2 % of
// itself, 2.8e-4 of the scene's; the AVX2 and the baseline kernels differ by 3.4e-5 of it. So each
// energy is also allowed 5e-4 of the scene's stored kinetic plus elastic energy (about twice that
// measured effect; a 1 % stiffer material still moves the main scene's energies by 1.5x what they
// are allowed, and its torque by 1.6x), at least 1e-9 J.
constexpr double kRelative = 2e-3;
constexpr double kSceneEnergyShare = 5e-4;
constexpr double kForceRelative = 5e-2;
constexpr double kSceneFloor = 1e-3;
constexpr double kEnergyFloor = 1e-9;  // J
constexpr double kLengthFloor = 1e-9;  // m
constexpr int kDefaultSteps = 50;

std::string scenesDir() {
  return TORSION_SCENES_DIR;
}
std::string metricsPath() {
  return std::string(TORSION_TEST_DATA) + "/regression/scene_metrics.json";
}

std::string toolchain() {
#if defined(__clang__)
  std::string id =
      "clang-" + std::to_string(__clang_major__) + "." + std::to_string(__clang_minor__);
#elif defined(__GNUC__)
  std::string id = "gcc-" + std::to_string(__GNUC__) + "." + std::to_string(__GNUC_MINOR__);
#else
  std::string id = "unknown";
#endif
#if defined(__x86_64__)
  id += "-x86_64";
#elif defined(__aarch64__)
  id += "-aarch64";
#endif
#if defined(NDEBUG)
  id += "-release";
#else
  id += "-debug";
#endif
#if defined(__SANITIZE_ADDRESS__)
  id += "-asan";
#endif
  if (!torsion::kBulletIsDouble) id += "-bullet-float";  // another build of Bullet: another state
  // The operator's kernels are chosen at run time by the CPU (AVX2+FMA or the baseline); they
  // round differently, so each has its own states.
  const std::string kernels = torsion::SystemOperator::bestKernelPath();
  if (kernels != "avx2+fma") id += "-" + kernels;
  return id;
}

struct Metrics {
  int steps = 0;
  double kinetic = 0, elastic = 0, max_displacement = 0;
  std::vector<std::pair<std::string, std::array<double, 6>>> wrenches;
  int contacts = -1;  ///< -1: the scene has no rigid bodies
  std::string hash;
};

Metrics runScenePath(const std::string& path, int steps, int threads, double stiffness_factor = 1) {
  Metrics m;
  Result<SceneSpec> spec = loadScene(path);
  if (!spec) {
    ADD_FAILURE() << spec.error().message;
    return m;
  }
  for (BodySpec& b : spec.value().bodies)
    b.material.youngs_modulus *= stiffness_factor;
  auto built = buildScene(std::move(spec).value(), BuildOptions{threads});
  if (!built) {
    ADD_FAILURE() << built.error().message;
    return m;
  }
  BuiltScene& s = *built.value();
  for (int k = 0; k < steps; ++k) {
    Result<WorldStepReport> stepped = stepScene(s);  // device hands: lockstep haptics
    if (!stepped) {
      ADD_FAILURE() << stepped.error().message;
      return m;
    }
    const WorldStepReport& r = stepped.value();
    if (!r.ok) {
      ADD_FAILURE() << path << ": " << r.message;
      return m;
    }
    m.steps = k + 1;
  }
  // FNV-1a over the bytes of every body's positions and velocities and every rigid body's pose
  // and velocity.
  Fnv1a fnv;
  for (const auto& body : s.world->bodies()) {
    m.kinetic += body->lastReport().kinetic_energy;
    m.elastic += body->lastReport().elastic_energy;
    const FemState& st = body->state();
    const auto& rest = body->model().mesh().restPositions();
    for (int i = 0; i < body->model().nodeCount(); ++i)
      m.max_displacement =
          std::max(m.max_displacement, (st.position(i) - rest[static_cast<size_t>(i)]).norm());
    fnv.add(st.positions.data(), sizeof(double) * static_cast<size_t>(st.positions.size()));
    fnv.add(st.velocities.data(), sizeof(double) * static_cast<size_t>(st.velocities.size()));
  }
  for (SceneHand& h : s.hands) {
    const Wrench w = h.hand->wrench();
    m.wrenches.push_back(
        {h.spec.name,
         {w.force.x(), w.force.y(), w.force.z(), w.torque.x(), w.torque.y(), w.torque.z()}});
  }
  for (NodeSetHandle& n : s.node_sets) {
    const Wrench w = n.body->groupWrench(n.group, n.wrench_about);
    m.wrenches.push_back(
        {n.name,
         {w.force.x(), w.force.y(), w.force.z(), w.torque.x(), w.torque.y(), w.torque.z()}});
  }
  if (!s.world->rigidBodies().empty()) {
    m.contacts = 0;
    for (const auto& body : s.world->bodies())
      m.contacts += body->contacts().stats().active;  // FEM-rigid contacts (docs/contact.md)
    for (btRigidBody* rb : s.world->rigidBodies()) {
      const btTransform& t = rb->getWorldTransform();
      for (int a = 0; a < 3; ++a) {
        fnv.add(t.getOrigin()[a]);
        fnv.add(rb->getLinearVelocity()[a]);
        fnv.add(rb->getAngularVelocity()[a]);
      }
      fnv.add(t.getRotation().x());
      fnv.add(t.getRotation().y());
      fnv.add(t.getRotation().z());
      fnv.add(t.getRotation().w());
    }
  }
  std::ostringstream hex;
  hex << std::hex << fnv.value();
  m.hash = hex.str();
  return m;
}

json toJson(const Metrics& m) {
  json j;
  j["steps"] = m.steps;
  j["kinetic_energy"] = m.kinetic;
  j["elastic_energy"] = m.elastic;
  j["max_displacement"] = m.max_displacement;
  j["wrenches"] = json::object();
  for (const auto& [name, w] : m.wrenches)
    j["wrenches"][name] = w;
  if (m.contacts >= 0) j["contacts"] = m.contacts;
  return j;
}

void checkNear(double expected, double actual, double floor, const std::string& what,
               std::vector<std::string>& failures) {
  if (std::abs(actual - expected) <= kRelative * std::abs(expected) + floor) return;
  std::ostringstream m;
  m.precision(10);
  m << what << ": stored " << expected << ", now " << actual;
  failures.push_back(m.str());
}

// Every way `m` is out of tolerance against the stored entry; empty when it matches.
std::vector<std::string> compare(const json& entry, const Metrics& m) {
  std::vector<std::string> failures;
  const double energy_floor =
      std::max(kEnergyFloor, kSceneEnergyShare * (entry["kinetic_energy"].get<double>() +
                                                  entry["elastic_energy"].get<double>()));
  checkNear(entry["kinetic_energy"], m.kinetic, energy_floor, "kinetic energy", failures);
  checkNear(entry["elastic_energy"], m.elastic, energy_floor, "elastic energy", failures);
  checkNear(entry["max_displacement"], m.max_displacement, kLengthFloor, "max displacement",
            failures);
  double force_scale = 0, torque_scale = 0;
  for (const auto& [set, w] : entry["wrenches"].items()) {
    const std::vector<double> v = w.get<std::vector<double>>();
    force_scale = std::max(force_scale, std::hypot(v[0], v[1], v[2]));
    torque_scale = std::max(torque_scale, std::hypot(v[3], v[4], v[5]));
  }
  for (const auto& [set, w] : m.wrenches) {
    if (!entry["wrenches"].contains(set)) {
      failures.push_back("no stored wrench for " + set);
      continue;
    }
    const std::vector<double> ref = entry["wrenches"][set].get<std::vector<double>>();
    const double fmag = std::hypot(ref[0], ref[1], ref[2]),
                 tmag = std::hypot(ref[3], ref[4], ref[5]);
    for (size_t c = 0; c < 6; ++c) {
      const double allowed = c < 3 ? kForceRelative * fmag + kSceneFloor * force_scale
                                   : kRelative * tmag + kSceneFloor * torque_scale;
      if (std::abs(w[c] - ref[c]) <= allowed + 1e-12) continue;
      std::ostringstream msg;
      msg.precision(10);
      msg << "wrench " << set << "[" << c << "]: stored " << ref[c] << ", now " << w[c]
          << " (allowed " << allowed << ")";
      failures.push_back(msg.str());
    }
  }
  if (m.contacts >= 0 && entry.contains("contacts")) {
    // Contacts are counted per node: a node at the collision margin may come or go.
    const int ref = entry["contacts"];
    if (std::abs(m.contacts - ref) > std::max(2, ref / 10))
      failures.push_back("contacts: stored " + std::to_string(ref) + ", now " +
                         std::to_string(m.contacts));
  }
  return failures;
}

std::string join(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines)
    s += "\n  " + l;
  return s;
}

std::vector<std::string> sceneNames() {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(scenesDir())) {
    if (entry.path().extension() == ".json") names.push_back(entry.path().stem().string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

json loadStored() {
  std::ifstream in(metricsPath());
  if (!in) return json{{"scenes", json::object()}};
  return json::parse(in);
}

class SceneRegression : public ::testing::TestWithParam<std::string> {};

TEST_P(SceneRegression, MetricsAndStateHash) {
  const std::string name = GetParam();
  const std::string path = scenesDir() + "/" + name + ".json";
  json stored = loadStored();
  const bool update = std::getenv("TORSION_UPDATE_REGRESSION") != nullptr;
  json entry = stored["scenes"].contains(name) ? stored["scenes"][name] : json();
  const int steps = entry.contains("steps") ? entry["steps"].get<int>() : kDefaultSteps;

  const Metrics one = runScenePath(path, steps, 1);
  const Metrics two = runScenePath(path, steps, 2);
  ASSERT_EQ(one.steps, steps) << "the scene did not run its steps";
  // Bit-identical for any thread count (docs/architecture.md, "Threads").
  EXPECT_EQ(one.hash, two.hash) << name << ": the state differs between 1 and 2 threads";
  const std::string tc = toolchain();

  if (update) {
    json fresh = toJson(one);
    if (entry.contains("state_hash")) fresh["state_hash"] = entry["state_hash"];
    fresh["state_hash"][tc] = {{"1", one.hash}, {"2", two.hash}};
    stored["scenes"][name] = fresh;
    std::ofstream(metricsPath()) << stored.dump(2) << "\n";
    GTEST_SKIP() << "stored metrics of " << name << " in " << metricsPath();
  }
  ASSERT_FALSE(entry.is_null())
      << name << " has no stored metrics in " << metricsPath()
      << ". Add them with TORSION_UPDATE_REGRESSION=1 (see the top of regression_test.cpp); "
      << "this run measured: " << toJson(one).dump();

  const std::vector<std::string> failures = compare(entry, one);
  EXPECT_TRUE(failures.empty()) << name << " after " << steps << " steps:" << join(failures);
  if (entry.contains("state_hash") && entry["state_hash"].contains(tc)) {
    EXPECT_EQ(entry["state_hash"][tc]["1"].get<std::string>(), one.hash)
        << name << ": state hash changed on this toolchain (" << tc
        << "); if intended, refresh with TORSION_UPDATE_REGRESSION=1";
  } else {
    std::cout << name << ": no stored state hash for toolchain " << tc << "\n";
  }
}

// The tolerances are tight enough to see physics: the main scene with a 1 % stiffer material
// must fail the comparison.
TEST(SceneRegressionTolerances, OnePercentStifferMaterialIsCaught) {
  const std::string name = "twist_cylinder_2430";
  const json stored = loadStored();
  if (!stored["scenes"].contains(name)) GTEST_SKIP() << "no stored metrics for " << name;
  const json& entry = stored["scenes"][name];
  const Metrics m = runScenePath(scenesDir() + "/" + name + ".json", entry["steps"], 1, 1.01);
  const std::vector<std::string> failures = compare(entry, m);
  EXPECT_FALSE(failures.empty());
  std::cout << "E x 1.01 is caught by:" << join(failures) << "\n";
}

INSTANTIATE_TEST_SUITE_P(Scenes, SceneRegression, ::testing::ValuesIn(sceneNames()),
                         [](const ::testing::TestParamInfo<std::string>& param_info) {
                           std::string n = param_info.param;
                           for (char& c : n) {
                             if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                           }
                           return n;
                         });

}  // namespace
}  // namespace torsion::scene
