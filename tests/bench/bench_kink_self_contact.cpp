// The 2430-tet cylinder twisted past its kink with self-contact on (docs/validation-twist.md,
// "Twisting past the kink"): the test scene of tests/physics/twist_past_kink_test.cpp (r = 1, L =
// 10, E = 1e5 Pa, dt = 0.01 s, 0.5 rad/s up to 4 pi, then held), with the body's self-contact.
// After every step from --check-from on, the exact surface-intersection checker
// (analysis/surface_intersections.h) looks for crossing surface triangles; the first crossing
// pairs are printed with their rest positions (are they neighbours folding, or the loop passing
// through the bar?), and every --print steps the twist state: hand torque, elastic and kinetic
// energy, active contacts, contact iterations.
//
//   bench_kink_self_contact [--friction MU] [--dt S] [--rate RAD_PER_S] [--hold STEPS]
//                           [--check-from STEP] [--print STEPS] [--detail STEP]
//                           [--no-self-contact] [--barrier-threshold J0] [--barrier-stiffness K]
//                           [--angle TURN_IN_PI]
// --detail prints that step's crossing pairs and the contacts on them, as for the first one.
// --barrier-threshold / --barrier-stiffness set the material's volume barrier
// (fem/volume_barrier.h; threshold 0 turns it off, as the code was before it existed).
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "crossing_kinds.h"
#include "torsion/analysis/step_anomalies.h"
#include "torsion/analysis/surface_intersections.h"
#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/mesh_io.h"

using namespace torsion;

int main(int argc, char** argv) {
  double friction = 0.3, dt = 0.01, rate = 0.5, max_angle = 4 * M_PI;
  int hold = 300, check_from = 0, print_every = 100, detail_step = -1;
  bool self_contact = true;
  Material material;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() { return i + 1 < argc ? std::atof(argv[++i]) : 0.0; };
    if (arg == "--friction")
      friction = value();
    else if (arg == "--dt")
      dt = value();
    else if (arg == "--rate")
      rate = value();
    else if (arg == "--hold")
      hold = static_cast<int>(value());
    else if (arg == "--check-from")
      check_from = static_cast<int>(value());
    else if (arg == "--print")
      print_every = std::max(1, static_cast<int>(value()));
    else if (arg == "--detail")
      detail_step = static_cast<int>(value());
    else if (arg == "--no-self-contact")
      self_contact = false;
    else if (arg == "--angle")
      max_angle = value() * M_PI;
    else if (arg == "--barrier-threshold")
      material.barrier_threshold = value();
    else if (arg == "--barrier-stiffness")
      material.barrier_stiffness = value();
    else {
      std::fprintf(stderr, "unknown argument '%s'\n", arg.c_str());
      return 2;
    }
  }
  Result<LoadedMesh> loaded = readMesh(std::string(TORSION_ASSETS_DIR) + "/cylinder_2430.node");
  if (!loaded.ok()) {
    std::fprintf(stderr, "%s\n", loaded.error().message.c_str());
    return 1;
  }
  const TetMesh& mesh = loaded.value().mesh;
  WorldSettings settings;
  settings.gravity.setZero();
  settings.solver.time_step = dt;
  FemWorld world(settings);
  FemBody* body = world.addBody("bar", mesh, material).value();
  if (self_contact) {
    SelfContactSettings contact;
    contact.friction = friction;
    if (!body->enableSelfContact(contact).ok()) return 1;
  }
  const double length = 10;
  std::vector<int> base, top;
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    const double z = mesh.restPositions()[static_cast<size_t>(n)].z();
    if (z < 1e-9) base.push_back(n);
    if (z > length - 1e-9) top.push_back(n);
  }
  body->carryNodes(
      "base", base, [](double) { return Frame{}; }, 0);
  const int hand = body->carryNodes(
      "top", top,
      [=](double t) {
        Frame f;
        f.origin = Eigen::Vector3d(0, 0, length);
        f.rotation = Eigen::AngleAxisd(std::min(rate * t, max_angle), Eigen::Vector3d::UnitZ());
        return f;
      },
      0);
  StepAnomalyMonitor monitor;
  const int steps = static_cast<int>(std::ceil(max_angle / rate / dt)) + hold;
  const auto start = std::chrono::steady_clock::now();
  int crossing_steps = 0, first_crossing = -1, unconverged = 0, checked = 0;
  // Over the steps with crossings: pairs by kind (crossing_kinds.h), summed.
  CrossingKinds kinds_total;
  int deep_crossing_steps = 0;  // steps with a pair deeper than the gap tolerance
  double peak_elastic = 0;
  int peak_inverted = 0, peak_barrier = 0, inverted_steps = 0;
  double peak_torque = 0;
  for (int k = 1; k <= steps; ++k) {
    if (!world.step().ok) {
      std::printf("step %d failed: %s\n", k, body->lastReport().message.c_str());
      return 1;
    }
    const StepReport& r = body->lastReport();
    peak_elastic = std::max(peak_elastic, r.elastic_energy);
    const StepObservation observation = observeStep(body->model(), body->state().positions, r);
    peak_inverted = std::max(peak_inverted, observation.inverted_elements);
    peak_barrier = std::max(peak_barrier, r.barrier_tets);
    if (observation.inverted_elements > 0) ++inverted_steps;
    for (AnomalyKind kind : monitor.observe(k, observation))
      std::printf("step %d: %s starts\n", k, toString(kind));
    peak_torque = std::max(
        peak_torque, std::abs(body->groupWrench(hand, Eigen::Vector3d(0, 0, length)).torque.z()));
    const SelfContactSolver* contact = body->selfContact();
    if (contact != nullptr && !contact->stats().converged) ++unconverged;
    int crossings = -1;
    if (k >= check_from) {
      ++checked;
      const std::vector<TrianglePair> pairs =
          findSurfaceIntersections(mesh.surfaceTriangles(), body->state().positions);
      crossings = static_cast<int>(pairs.size());
      if (!pairs.empty()) {
        ++crossing_steps;
        const CrossingKinds kinds = classifyCrossings(
            pairs, mesh.surfaceTriangles(), body->state().positions,
            contact != nullptr ? contact->contacts() : std::vector<SurfaceContact>{},
            contact != nullptr ? contact->settings().max_depth : 0.25,
            contact != nullptr ? contact->gapTolerance() : 0.0);
        kinds_total.node_in_face += kinds.node_in_face;
        kinds_total.node_in_face_deep += kinds.node_in_face_deep;
        kinds_total.edge_edge += kinds.edge_edge;
        kinds_total.with_candidate += kinds.with_candidate;
        kinds_total.edge_edge_with_candidate += kinds.edge_edge_with_candidate;
        kinds_total.within_tolerance += kinds.within_tolerance;
        kinds_total.deepest = std::max(kinds_total.deepest, kinds.deepest);
        if (kinds.within_tolerance < crossings && deep_crossing_steps++ == 0)
          std::printf(
              "step %d: first pair deeper than the gap tolerance (%.3g m): %d of %d pairs "
              "(%d edge-edge), deepest %.3g m, active contacts %d\n",
              k, contact != nullptr ? contact->gapTolerance() : 0.0,
              crossings - kinds.within_tolerance, crossings, kinds.edge_edge, kinds.deepest,
              contact != nullptr ? contact->stats().active : 0);
        if (first_crossing < 0 || k % print_every == 0)
          std::printf(
              "step %d: %d crossing pairs: %d node in face (%d deep), %d edge-edge; %d with a "
              "candidate (%d edge-edge); %d within the gap tolerance, deepest %.3g m\n",
              k, crossings, kinds.node_in_face, kinds.node_in_face_deep, kinds.edge_edge,
              kinds.with_candidate, kinds.edge_edge_with_candidate, kinds.within_tolerance,
              kinds.deepest);
      }
      if (!pairs.empty() && (first_crossing < 0 || k == detail_step)) {
        if (first_crossing < 0) first_crossing = k;
        const std::vector<Triangle>& triangles = mesh.surfaceTriangles();
        for (const TrianglePair& p : pairs) {
          Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
          for (int c : triangles[static_cast<size_t>(p.first)])
            a += mesh.restPositions()[static_cast<size_t>(c)] / 3;
          for (int c : triangles[static_cast<size_t>(p.second)])
            b += mesh.restPositions()[static_cast<size_t>(c)] / 3;
          std::printf(
              "step %d: triangles %d and %d cross; rest centroids (%.2f %.2f %.2f) and "
              "(%.2f %.2f %.2f), %.3f m apart\n",
              k, p.first, p.second, a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), (a - b).norm());
          // The contacts this step had on the pair: why did they not hold it?
          const Triangle& tp = triangles[static_cast<size_t>(p.first)];
          const Triangle& tq = triangles[static_cast<size_t>(p.second)];
          auto in = [](const Triangle& t, int n) { return t[0] == n || t[1] == n || t[2] == n; };
          for (const SurfaceContact& c :
               contact != nullptr ? contact->contacts() : std::vector<SurfaceContact>{}) {
            const bool covers = c.edge < 0 ? (c.triangle == p.second && in(tp, c.nodes[0])) ||
                                                 (c.triangle == p.first && in(tq, c.nodes[0]))
                                           : (in(tp, c.nodes[0]) && in(tp, c.nodes[1]) &&
                                              in(tq, c.nodes[2]) && in(tq, c.nodes[3])) ||
                                                 (in(tq, c.nodes[0]) && in(tq, c.nodes[1]) &&
                                                  in(tp, c.nodes[2]) && in(tp, c.nodes[3]));
            if (!covers) continue;
            std::printf(
                "  %s contact: gap %.3g m, linearised end gap %.3g m, state %d, "
                "normal impulse %.3g N s\n",
                c.edge < 0 ? "node-triangle" : "edge-edge", c.gap, c.end_gap,
                static_cast<int>(c.state), c.normal.dot(c.multiplier));
          }
        }
      }
    }
    if (k % print_every == 0) {
      const Wrench w = body->groupWrench(hand, Eigen::Vector3d(0, 0, length));
      std::printf(
          "step %d: twist %.3f pi, hand torque %.5g N m, elastic %.5g J, kinetic %.4g J, "
          "active contacts %d, contact iterations %d, crossing pairs %d, inverted tets %d, "
          "tets in the barrier %d\n",
          k, std::min(rate * k * dt, max_angle) / M_PI, std::abs(w.torque.z()), r.elastic_energy,
          r.kinetic_energy, contact ? contact->stats().active : 0,
          contact ? contact->stats().iterations : 0, crossings, observation.inverted_elements,
          r.barrier_tets);
    }
  }
  const Wrench w = body->groupWrench(hand, Eigen::Vector3d(0, 0, length));
  std::printf(
      "end: hand torque %.5g N m, elastic %.5g J (peak %.5g J), steps with crossing triangles %d "
      "of %d checked (first %d), unconverged contact solves %d, %.1f s\n"
      "crossing pairs summed over those steps: %d node in face (%d deep), %d edge-edge; %d with "
      "a candidate (%d edge-edge); %d within the gap tolerance, deepest %.3g m; steps with a "
      "pair deeper than the tolerance %d\n"
      "inverted tets: at most %d, in %d steps; tets in the barrier: at most %d; peak hand torque "
      "%.5g N m\n",
      std::abs(w.torque.z()), body->lastReport().elastic_energy, peak_elastic, crossing_steps,
      checked, first_crossing, unconverged,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
      kinds_total.node_in_face, kinds_total.node_in_face_deep, kinds_total.edge_edge,
      kinds_total.with_candidate, kinds_total.edge_edge_with_candidate,
      kinds_total.within_tolerance, kinds_total.deepest, deep_crossing_steps, peak_inverted,
      inverted_steps, peak_barrier, peak_torque);
  for (const Anomaly& a : monitor.anomalies())
    std::printf("anomaly %s: steps %d-%d, peak %g\n", toString(a.kind), a.first_step, a.last_step,
                a.peak);
  return 0;
}
