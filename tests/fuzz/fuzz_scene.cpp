// libFuzzer target for the scene loader: parseScene on the input as a scene file, and when it
// parses, buildScene and two steps. Every input must end in one of: a parse error, a build error,
// a failed step, each a message naming the file (and, for parse errors, the key or position);
// or two good steps whose state is finite. Never a crash, a hang, or a
// step that reports success on garbage.
//
// Seeds are the shipped demo scenes (demos/scenes) plus regressions in corpus/scene. Besides
// libFuzzer's byte mutations, a structural mutator (LLVMFuzzerCustomMutator below) edits the
// parsed JSON: deletes keys, changes types, puts in extreme numbers, NaN-like strings, numbers
// beyond a double, huge arrays and deep nesting.
//
// Building is skipped where it would make a case slow or touch the machine: a mesh file over
// kMaxMeshBytes, a network or SpaceMouse device (sockets, a daemon), a .bullet file. Those
// inputs are still parsed.

#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_checks.h"
#include "scene_builder.h"
#include "scene_parser.h"

#ifndef TORSION_FUZZ_SCENES_DIR
#error "TORSION_FUZZ_SCENES_DIR: the demo scenes' directory, against which mesh paths resolve"
#endif

namespace {

using torsion::fuzz::startsWith;
constexpr const char* kFile = "fuzz.json";
// Meshes built and stepped (by their .node file's size): a case stays well under a second under
// ASan. cylinder_2430 as tet4 is in; as tet10 (7 times the nodes) only the small blocks are.
constexpr long kMaxMeshBytes = 40 * 1000;
constexpr long kMaxTet10MeshBytes = 8 * 1000;
constexpr int kSteps = 2;
constexpr int kMaxNewtonIterations = 3;
constexpr int kMaxIterations = 15;

// What a user reads: it names the file, and it is valid UTF-8 (the scene's strings are JSON, so
// they are; a message that cut one in the middle would not be). Control characters from the
// scene's strings may appear: the torsion tool shows them escaped (cli/text_only_stderr.h).
void checkMessage(const std::string& message) {
  TORSION_FUZZ_CHECK(!message.empty());
  TORSION_FUZZ_CHECK(startsWith(message, kFile));
  size_t k = 0;
  while (k < message.size()) {
    const auto c = static_cast<unsigned char>(message[k]);
    size_t length = 1;
    if (c >= 0x80) {
      length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : 2;
      TORSION_FUZZ_CHECK(c >= 0xc2 && c <= 0xf4 && k + length <= message.size());
      for (size_t j = 1; j < length; ++j)
        TORSION_FUZZ_CHECK((static_cast<unsigned char>(message[k + j]) & 0xc0) == 0x80);
    }
    k += length;
  }
}

bool quickToBuild(const torsion::scene::SceneSpec& spec) {
  if (!spec.bullet_file.empty()) return false;
  for (const torsion::scene::BodySpec& body : spec.bodies) {
    struct stat info {};
    const long cap =
        body.element == torsion::ElementKind::kTet10 ? kMaxTet10MeshBytes : kMaxMeshBytes;
    if (::stat(body.mesh_path.c_str(), &info) == 0 && info.st_size > cap) return false;
    // A .node's .ele sibling is of the same order; other paths fail to load quickly.
  }
  for (const torsion::scene::HandSpec& hand : spec.hands) {
    if (hand.device && (hand.device->kind == torsion::scene::DeviceSpec::Kind::kNetwork ||
                        hand.device->kind == torsion::scene::DeviceSpec::Kind::kSpaceMouse))
      return false;
  }
  return true;
}

void checkFinite(const torsion::scene::BuiltScene& scene) {
  for (const auto& body : scene.world->bodies()) {
    TORSION_FUZZ_CHECK(body->state().positions.allFinite());
    TORSION_FUZZ_CHECK(body->state().velocities.allFinite());
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  torsion::Result<torsion::scene::SceneSpec> spec =
      torsion::scene::parseScene(text, kFile, TORSION_FUZZ_SCENES_DIR);
  if (!spec.ok()) {
    checkMessage(spec.error().message);
    return 0;
  }
  TORSION_FUZZ_CHECK(spec.value().steps >= 0);
  TORSION_FUZZ_CHECK(std::isfinite(spec.value().world.solver.time_step) &&
                     spec.value().world.solver.time_step > 0);
  if (!quickToBuild(spec.value())) return 0;
  // The step budget: a few CG iterations (an unconverged solve is a reported failure, which is
  // one of the outcomes checked) keep a case short under ASan, which runs the solver some 70
  // times slower than Release: a thin sheet pressed by a box (30 contact rounds a step, each a CG
  // solve) took 10 s at 40 iterations.
  int& iterations = spec.value().world.solver.max_iterations;
  iterations = std::min(iterations, kMaxIterations);
  // A hyperelastic body's step is up to newton_max_iterations such solves.
  int& newton_iterations = spec.value().world.solver.newton_max_iterations;
  newton_iterations = std::min(newton_iterations, kMaxNewtonIterations);

  auto built = torsion::scene::buildScene(std::move(spec).value(), torsion::scene::BuildOptions{1});
  if (!built.ok()) {
    checkMessage(built.error().message);
    return 0;
  }
  torsion::scene::BuiltScene& scene = *built.value();
  checkFinite(scene);
  for (int k = 0; k < kSteps; ++k) {
    if (torsion::Status driven = torsion::scene::driveHands(scene); !driven.ok()) {
      checkMessage(driven.error().message);
      return 0;
    }
    const torsion::WorldStepReport report = scene.world->step();
    if (!report.ok) {
      TORSION_FUZZ_CHECK(!report.message.empty());
      return 0;
    }
    checkFinite(scene);  // a step that says ok has a finite state
  }
  return 0;
}

// ---- Structural mutations (libFuzzer's custom mutator hook; not in replay builds) ----------

#ifdef TORSION_FUZZ_STRUCTURAL
extern "C" size_t LLVMFuzzerMutate(uint8_t* data, size_t size, size_t max_size);

namespace {

using Json = nlohmann::ordered_json;

// Every node of `root`, without recursion; false when nesting is deeper than `max_depth` (dump()
// recurses: such a document is left to the byte mutations).
bool collect(Json& root, std::vector<Json*>& into, int max_depth) {
  std::vector<std::pair<Json*, int>> stack{{&root, 0}};
  while (!stack.empty()) {
    auto [node, depth] = stack.back();
    stack.pop_back();
    if (depth > max_depth) return false;
    into.push_back(node);
    if (node->is_object() || node->is_array()) {
      for (Json& child : *node)
        stack.push_back({&child, depth + 1});
    }
  }
  return true;
}

// Placeholders replaced in the dumped text by tokens a JSON value cannot hold.
const char* const kRawTokens[] = {"1e400",
                                  "-1e400",
                                  "NaN",
                                  "Infinity",
                                  "-0",
                                  "1e-400",
                                  "18446744073709551616",
                                  "-9223372036854775809"};

Json extremeNumber(std::mt19937& random) {
  const Json values[] = {0,          -0.0,        1e308,      -1e308, 5e-324, 1e-300, 2147483647,
                         2147483648, -2147483649, 4294967296, 1e18,   9.3e18, -1,     1e6,
                         1e15,       0.5,         -1e-12,     65536,  1e100,  -1e100};
  return values[random() % (sizeof values / sizeof values[0])];
}

Json nanLikeString(std::mt19937& random) {
  const char* const strings[] = {"NaN",
                                 "nan",
                                 "inf",
                                 "-Infinity",
                                 "1e999",
                                 "0x10",
                                 "",
                                 "\u00e9\u00e8",
                                 "\u0001\u0002",
                                 "../../../../dev/zero",
                                 "/dev/zero",
                                 "/proc/self/fd/0",
                                 "tet10",
                                 "tet4",
                                 "network"};
  return strings[random() % (sizeof strings / sizeof strings[0])];
}

bool mutateNode(Json& root, std::mt19937& random, std::vector<std::string>& raw, size_t max_size) {
  std::vector<Json*> nodes;
  if (!collect(root, nodes, 4000)) return false;
  Json& node = *nodes[random() % nodes.size()];
  switch (random() % 9) {
    case 0:  // delete a key or an element
      if (node.is_object() && !node.empty()) {
        auto it = node.begin();
        std::advance(it, static_cast<long>(random() % node.size()));
        node.erase(it);
      } else if (node.is_array() && !node.empty()) {
        node.erase(node.begin() + static_cast<long>(random() % node.size()));
      }
      break;
    case 1: {  // change the type
      const Json others[] = {nullptr, true, "text", 1, Json::array(), Json::object(), 0.25};
      node = others[random() % 7];
      break;
    }
    case 2:
      node = extremeNumber(random);
      break;
    case 3:
      node = nanLikeString(random);
      break;
    case 4: {  // a token no JSON value holds, spliced in as text
      const std::string token = kRawTokens[random() % (sizeof kRawTokens / sizeof kRawTokens[0])];
      node = "@@raw" + std::to_string(raw.size()) + "@@";
      raw.push_back(token);
      break;
    }
    case 5: {  // a huge array, of a number or of the node's first element when that is small
      const size_t n = size_t{1} << (8 + random() % 10);  // 256 .. 131072
      Json element = node.is_array() && !node.empty() ? node[0] : Json(1.0);
      if (element.dump().size() * n > max_size) element = 0;
      if (2 * n > max_size) break;
      node = Json::array();
      for (size_t k = 0; k < n; ++k)
        node.push_back(element);
      break;
    }
    case 6: {                                      // deep nesting
      const int depth = 1 << (2 + random() % 11);  // 4 .. 4096
      if (node.dump().size() + 2 * static_cast<size_t>(depth) > max_size) break;
      Json inner = node;
      for (int k = 0; k < depth; ++k)
        inner = Json::array({std::move(inner)});
      node = std::move(inner);
      break;
    }
    case 7: {  // a subtree copied over another (each copy may double the document)
      const Json copy = *nodes[random() % nodes.size()];
      if (copy.dump().size() > max_size / 4) break;
      node = copy;
      break;
    }
    case 8:  // numbers nudged: near a bound, negative, tiny
      if (node.is_number()) {
        const double v = node.get<double>();
        const double choices[] = {-v, v * 1e10, v * 1e-10, std::nextafter(v, 0.0), v + 1};
        node = choices[random() % 5];
      }
      break;
  }
  return true;
}

}  // namespace

extern "C" size_t LLVMFuzzerCustomMutator(uint8_t* data, size_t size, size_t max_size,
                                          unsigned int mutation_seed) {
  std::mt19937 rng(mutation_seed);
  if (rng() % 2 == 0) return LLVMFuzzerMutate(data, size, max_size);
  Json root = Json::parse(data, data + size, nullptr, false);
  if (root.is_discarded()) return LLVMFuzzerMutate(data, size, max_size);
  std::vector<std::string> raw;
  const int edits = 1 + static_cast<int>(rng() % 3);
  for (int k = 0; k < edits; ++k) {
    if (!mutateNode(root, rng, raw, max_size)) return LLVMFuzzerMutate(data, size, max_size);
  }
  std::string text = root.dump(1);
  for (size_t k = 0; k < raw.size(); ++k) {
    const std::string placeholder = "\"@@raw" + std::to_string(k) + "@@\"";
    if (const size_t at = text.find(placeholder); at != std::string::npos)
      text.replace(at, placeholder.size(), raw[k]);
  }
  if (text.size() > max_size) return LLVMFuzzerMutate(data, size, max_size);
  std::copy(text.begin(), text.end(), data);
  return text.size();
}
#endif
