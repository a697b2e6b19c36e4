// Self-contact over a whole scene (docs/performance-contact.md, "Self-contact on the plectoneme
// rod"; docs/contact.md, "Self-contact"): steps/s, and per body with self-contact the steps whose
// contact solve stopped unconverged, the most active contacts, the deepest linearised end-of-step
// penetration, the tree searches, the island's Newton iterations, and every `--check-every` steps
// whether any two surface triangles intersect (analysis/surface_intersections.h, exact). One JSON
// line on stdout.
//
//   bench_self_contact SCENE [--steps N] [--threads T] [--check-every K]
//                            [--save-at K FILE] [--resume FILE] [--self-contact off]
//                            [--search-skin S] [--thickness FACTOR] [--per-step 1]
//
// --save-at writes a checkpoint (checkpoint_io.h) after step K; --resume starts from one, so that
// the contact phase (the plectoneme's last ~350 steps) can be profiled alone. `--self-contact off`
// runs the same scene with the body's self-contact turned off (the cost of having it on);
// `--thickness` with its thickness_factor (docs/contact.md, "Contact thickness"; 0: none);
// `--per-step 1` prints each step's contact figures and each check's crossings on stderr.
// search_ms_per_step is the wall time of self-contact's tree searches (SelfContactStats),
// search_builds how many of them walked the tree (the others reused the pairs kept across
// steps); `--search-skin S` sets SelfContactSettings::search_skin (0: a fresh search every step).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
#include <string>

#include "crossing_kinds.h"
#include "scene_builder.h"
#include "scene_haptics.h"
#include "scene_parser.h"
#include "torsion/analysis/surface_intersections.h"
#include "torsion/bullet/checkpoint_io.h"

int main(int argc, char** argv) {
  using namespace torsion;
  using namespace torsion::scene;
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: %s SCENE [--steps N] [--threads T] [--check-every K] [--save-at K FILE] "
                 "[--resume FILE] [--self-contact off] [--search-skin S] [--thickness F] "
                 "[--per-step 1]\n",
                 argv[0]);
    return 1;
  }
  int steps = -1, threads = -1, check_every = 50, save_at = -1;
  std::string save_file, resume_file;
  bool self_contact = true;
  double search_skin = -1;  // -1: the scene's (or the checkpoint's)
  double thickness = -1;    // --thickness: self-contact's thickness_factor (-1: the scene's)
  bool per_step = false;    // --per-step 1: each step's contact figures on stderr
  for (int a = 2; a + 1 < argc; a += 2) {
    if (!std::strcmp(argv[a], "--steps")) steps = std::atoi(argv[a + 1]);
    if (!std::strcmp(argv[a], "--threads")) threads = std::atoi(argv[a + 1]);
    if (!std::strcmp(argv[a], "--check-every")) check_every = std::atoi(argv[a + 1]);
    if (!std::strcmp(argv[a], "--resume")) resume_file = argv[a + 1];
    if (!std::strcmp(argv[a], "--search-skin")) search_skin = std::atof(argv[a + 1]);
    if (!std::strcmp(argv[a], "--thickness")) thickness = std::atof(argv[a + 1]);
    if (!std::strcmp(argv[a], "--per-step")) per_step = std::atoi(argv[a + 1]) != 0;
    if (!std::strcmp(argv[a], "--self-contact"))
      self_contact = std::strcmp(argv[a + 1], "off") != 0;
    if (!std::strcmp(argv[a], "--save-at") && a + 2 < argc) {
      save_at = std::atoi(argv[a + 1]);
      save_file = argv[++a + 1];
    }
  }
  Result<SceneSpec> spec = loadScene(argv[1]);
  if (!spec) {
    std::fprintf(stderr, "%s\n", spec.error().message.c_str());
    return 1;
  }
  if (steps < 0) steps = spec.value().steps;
  Result<std::unique_ptr<BuiltScene>> built =
      buildScene(std::move(spec.value()), BuildOptions{threads});
  if (!built) {
    std::fprintf(stderr, "%s\n", built.error().message.c_str());
    return 1;
  }
  BuiltScene& scene = *built.value();
  FemBody* body = nullptr;
  for (const auto& b : scene.world->bodies())
    if (b->selfContact() != nullptr) body = b.get();
  if (body == nullptr) {
    std::fprintf(stderr, "no body with self-contact in %s\n", argv[1]);
    return 1;
  }
  const double gap_tolerance = body->selfContact()->gapTolerance();
  std::vector<Hand*> hands;
  for (SceneHand& h : scene.hands)
    hands.push_back(h.hand.get());
  if (!resume_file.empty()) {
    std::ifstream in(resume_file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    Result<StoredCheckpoint> stored = readCheckpoint(bytes, *scene.world, hands);
    if (!stored) {
      std::fprintf(stderr, "%s: %s\n", resume_file.c_str(), stored.error().message.c_str());
      return 1;
    }
    if (Status restored = scene.world->restore(stored.value().world); !restored) {
      std::fprintf(stderr, "%s: %s\n", resume_file.c_str(), restored.error().message.c_str());
      return 1;
    }
    for (size_t h = 0; h < hands.size(); ++h)
      hands[h]->restore(stored.value().hands[h]);
  }
  // After a checkpoint's restore, which brings self-contact back as it was saved.
  if (!self_contact) body->disableSelfContact();
  if (self_contact && thickness >= 0) {
    // Turned on again with the other thickness (warm starts are lost: resume where none is
    // active, or from the start).
    SelfContactSettings settings = body->selfContact()->settings();
    settings.thickness_factor = thickness;
    if (Status on = body->enableSelfContact(settings); !on) {
      std::fprintf(stderr, "%s\n", on.error().message.c_str());
      return 1;
    }
  }
  if (search_skin >= 0 && body->selfContact() != nullptr) {
    // Through a checkpoint: the solver comes back as it was (warm starts), with the new skin.
    FemBodyCheckpoint c = body->checkpoint();
    c.self_contact_settings.search_skin = search_skin;
    body->restore(c);
  }
  const std::vector<Triangle>& surface = body->model().mesh().surfaceTriangles();
  double mean_edge = 0;  // m, of the rest surface (for --per-step's local folds)
  for (const Triangle& t : surface)
    for (size_t a = 0; a < 3; ++a)
      mean_edge += (body->model().mesh().restPositions()[static_cast<size_t>(t[a])] -
                    body->model().mesh().restPositions()[static_cast<size_t>(t[(a + 1) % 3])])
                       .norm();
  mean_edge /= 3.0 * static_cast<double>(std::max<size_t>(surface.size(), 1));
  int unconverged = 0, max_active = 0, searches = 0, search_builds = 0, crossing_checks = 0,
      crossing_first = -1, exact_crossing_checks = 0;
  CrossingKinds kinds;  // the exact checker's pairs at the checks, summed (crossing_kinds.h)
  long newton = 0;
  long cg = 0;  // the body's CG iterations (with contact: the island's, summed over Newton)
  double worst_end = 0, stepping = 0, searching = 0;
  const std::clock_t cpu0 = std::clock();
  for (int k = 1; k <= steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    Result<WorldStepReport> report = stepScene(scene);
    stepping += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!report || !report.value().ok) {
      std::fprintf(stderr, "step %d failed: %s\n", k,
                   report ? report.value().message.c_str() : report.error().message.c_str());
      return 2;
    }
    if (k == save_at) {
      std::vector<HandCheckpoint> hand_checkpoints;
      for (Hand* h : hands)
        hand_checkpoints.push_back(h->checkpoint());
      std::ofstream(save_file, std::ios::binary)
          << writeCheckpoint(*scene.world, scene.world->checkpoint(), hands, hand_checkpoints, "");
    }
    cg += body->lastReport().solve.iterations;
    if (body->selfContact() != nullptr) {
      const SelfContactStats& s = body->selfContact()->stats();
      unconverged += s.converged ? 0 : 1;
      newton += s.iterations;
      max_active = std::max(max_active, s.active);
      worst_end = std::max(worst_end, s.max_end_penetration);
      searches += s.searches;
      search_builds += s.search_builds;
      searching += s.search_seconds;
      if (per_step)
        std::fprintf(stderr,
                     "step %d: candidates %d, active %d, Newton %d, CG %d, searches %d, %s, end "
                     "penetration %.3g m\n",
                     k, s.candidates, s.active, s.iterations, body->lastReport().solve.iterations,
                     s.searches, s.converged ? "converged" : "UNCONVERGED", s.max_end_penetration);
    } else if (per_step) {
      std::fprintf(stderr, "step %d: CG %d\n", k, body->lastReport().solve.iterations);
    }
    if (check_every > 0 && k % check_every == 0) {
      const std::vector<Triangle>& triangles = surface;
      const std::vector<TrianglePair> pairs =
          findSurfaceIntersections(triangles, body->state().positions);
      if (!pairs.empty()) {
        ++crossing_checks;
        if (crossing_first < 0) crossing_first = k;
        ++exact_crossing_checks;
        const CrossingKinds found =
            classifyCrossings(pairs, triangles, body->state().positions,
                              body->selfContact() != nullptr ? body->selfContact()->contacts()
                                                             : std::vector<SurfaceContact>{},
                              0.25, gap_tolerance);
        kinds.node_in_face += found.node_in_face;
        kinds.node_in_face_deep += found.node_in_face_deep;
        kinds.edge_edge += found.edge_edge;
        kinds.with_candidate += found.with_candidate;
        kinds.edge_edge_with_candidate += found.edge_edge_with_candidate;
        kinds.within_tolerance += found.within_tolerance;
        kinds.deepest = std::max(kinds.deepest, found.deepest);
        if (per_step) {
          // Local folds (the two triangles' rest centroids within two mean edges: a kink's
          // inverted tets) apart from contact between distant parts of the surface.
          const std::vector<Eigen::Vector3d>& rest = body->model().mesh().restPositions();
          auto centroid = [&](int t) {
            Eigen::Vector3d c = Eigen::Vector3d::Zero();
            for (int n : triangles[static_cast<size_t>(t)])
              c += rest[static_cast<size_t>(n)];
            return Eigen::Vector3d(c / 3);
          };
          int local = 0;
          for (const TrianglePair& pr : pairs)
            if ((centroid(pr.first) - centroid(pr.second)).norm() < 2 * mean_edge) ++local;
          std::fprintf(stderr,
                       "step %d: %zu crossing pairs (%d local: rest centroids within two mean "
                       "edges), %d edge-edge, %d node in face beyond max_depth, %d with a "
                       "candidate, %d within the tolerance, deepest %.3g m\n",
                       k, pairs.size(), local, found.edge_edge, found.node_in_face_deep,
                       found.with_candidate, found.within_tolerance, found.deepest);
        }
      }
    }
  }
  const double cpu = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  std::printf(
      "{\"scene\": \"%s\", \"steps\": %d, \"threads\": %d, \"steps_per_s\": %.2f, "
      "\"cpu_s_per_step\": %.4g, \"search_ms_per_step\": %.3g, \"self_contact\": %s, "
      "\"newton_iterations\": %ld, \"cg_per_step\": %.1f, "
      "\"unconverged\": %d, \"max_active\": %d, "
      "\"worst_end_penetration_m\": %.3g, "
      "\"gap_tolerance_m\": %.3g, \"searches\": %d, \"search_builds\": %d, "
      "\"crossing_checks\": %d, "
      "\"first_crossing_step\": %d, \"exact_crossing_checks\": %d, "
      "\"crossing_pairs_node_in_face\": %d, \"crossing_pairs_node_in_face_deep\": %d, "
      "\"crossing_pairs_edge_edge\": %d, \"crossing_pairs_with_candidate\": %d, "
      "\"crossing_pairs_edge_edge_with_candidate\": %d, "
      "\"crossing_pairs_within_gap_tolerance\": %d, \"deepest_crossing_m\": %.3g}\n",
      scene.spec.name.c_str(), steps, threads, steps / stepping, cpu / steps,
      1e3 * searching / steps, self_contact ? "true" : "false", newton,
      static_cast<double>(cg) / steps, unconverged, max_active, worst_end, gap_tolerance, searches,
      search_builds, crossing_checks, crossing_first, exact_crossing_checks, kinds.node_in_face,
      kinds.node_in_face_deep, kinds.edge_edge, kinds.with_candidate,
      kinds.edge_edge_with_candidate, kinds.within_tolerance, kinds.deepest);
  return 0;
}
