// The self-contact search's pairs kept across steps (surface_pair_cache.h): over a moving scene
// they must give exactly the candidates a fresh search gives, step by step, while walking the
// tree only in a few steps.
#include "torsion/contact/surface_pair_cache.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "torsion/bullet/fem_body.h"
#include "torsion/bullet/fem_world.h"
#include "torsion/mesh/box_mesh.h"

namespace torsion {
namespace {

// Two cubes of side 0.1 m as one mesh, `gap` apart along x.
TetMesh twoCubes(double gap, int cells, int& second_first) {
  const TetMesh a =
      makeBoxTetMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(0.1), cells, cells, cells)
          .value();
  std::vector<Eigen::Vector3d> positions = a.restPositions();
  std::vector<Tet> tets = a.tets();
  second_first = a.nodeCount();
  for (const Eigen::Vector3d& x : a.restPositions())
    positions.push_back(x + Eigen::Vector3d(0.1 + gap, 0.02, 0));
  for (Tet t : a.tets()) {
    for (int& n : t)
      n += second_first;
    tets.push_back(t);
  }
  return TetMesh(std::move(positions), std::move(tets));
}

// Positions at time t: the second cube slides into the first (through it: the broad phase does
// not care) while turning, and every node wobbles on its own.
Eigen::VectorXd movedPositions(const TetMesh& mesh, int second_first, double t) {
  Eigen::VectorXd x(3 * mesh.nodeCount());
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.8 * t, Eigen::Vector3d::UnitZ()).matrix();
  const Eigen::Vector3d centre(0.17, 0.07, 0.05);
  for (int i = 0; i < mesh.nodeCount(); ++i) {
    Eigen::Vector3d p = mesh.restPositions()[static_cast<size_t>(i)];
    if (i >= second_first) p = centre + turn * (p - centre) - Eigen::Vector3d(0.06 * t, 0, 0);
    const double phase = 0.7 * i;
    p += 0.002 * Eigen::Vector3d(std::sin(9 * t + phase), std::cos(7 * t + 2 * phase),
                                 std::sin(5 * t + 3 * phase));
    x.segment<3>(3 * i) = p;
  }
  return x;
}

bool boxesWithin(const Eigen::Vector3d& lo_a, const Eigen::Vector3d& hi_a,
                 const Eigen::Vector3d& lo_b, const Eigen::Vector3d& hi_b, double margin) {
  return !(((lo_b.array() - margin) > hi_a.array()).any() ||
           ((hi_b.array() + margin) < lo_a.array()).any());
}

TEST(SurfacePairCache, KeptPairsAreExactlyAFreshSearchsOverAMovingSceneAndFewStepsWalkTheTree) {
  int second = 0;
  const TetMesh mesh = twoCubes(0.01, 4, second);
  const std::vector<Triangle>& triangles = mesh.surfaceTriangles();
  const SurfaceEdges edges(triangles);
  const std::vector<int>& nodes = mesh.surfaceNodes();
  const Parallel serial(1), parallel(2);
  SurfacePairCache fresh(triangles, edges, nodes), kept(triangles, edges, nodes);
  const double margin = 0.006, skin = 0.006;  // m (surface edges 25 mm, 2 mm wobble)
  const int steps = 200;
  long pairs = 0, later_pairs = 0;
  std::vector<int> a, b, scratch_a, scratch_b, out_a, out_b;
  for (int k = 0; k < steps; ++k) {
    const Eigen::VectorXd x = movedPositions(mesh, second, 0.01 * k);
    const Eigen::VectorXd end = movedPositions(mesh, second, 0.01 * (k + 1));
    fresh.prepare(x, end, margin, 0, serial);
    kept.prepare(x, end, margin, skin, parallel);
    for (size_t n = 0; n < nodes.size(); ++n) {
      const Eigen::Vector3d p = x.segment<3>(3 * nodes[n]), q = end.segment<3>(3 * nodes[n]);
      fresh.nodeTriangles(static_cast<int>(n), p.cwiseMin(q), p.cwiseMax(q), a);
      kept.nodeTriangles(static_cast<int>(n), p.cwiseMin(q), p.cwiseMax(q), b);
      ASSERT_EQ(a, b) << "step " << k << ", surface node " << n;
      pairs += static_cast<long>(a.size());
    }
    // Edges: what the solver keeps of each list (its box test within the margin, no shared node).
    std::vector<Eigen::Vector3d> lo(edges.edges.size()), hi(edges.edges.size());
    for (size_t i = 0; i < edges.edges.size(); ++i) {
      const std::array<int, 2>& e = edges.edges[i];
      const Eigen::Vector3d p0 = x.segment<3>(3 * e[0]), q0 = x.segment<3>(3 * e[1]);
      const Eigen::Vector3d p1 = end.segment<3>(3 * e[0]), q1 = end.segment<3>(3 * e[1]);
      lo[i] = p0.cwiseMin(q0).cwiseMin(p1).cwiseMin(q1);
      hi[i] = p0.cwiseMax(q0).cwiseMax(p1).cwiseMax(q1);
    }
    const auto keep = [&](int i, const std::vector<int>& later, std::vector<int>& out) {
      out.clear();
      const std::array<int, 2>& e = edges.edges[static_cast<size_t>(i)];
      for (int j : later) {
        const std::array<int, 2>& f = edges.edges[static_cast<size_t>(j)];
        if (f[0] == e[0] || f[0] == e[1] || f[1] == e[0] || f[1] == e[1]) continue;
        const size_t si = static_cast<size_t>(i), sj = static_cast<size_t>(j);
        if (boxesWithin(lo[si], hi[si], lo[sj], hi[sj], margin)) out.push_back(j);
      }
    };
    for (int i = 0; i < static_cast<int>(edges.edges.size()); ++i) {
      const size_t si = static_cast<size_t>(i);
      keep(i, fresh.laterEdges(i, lo[si], hi[si], scratch_a, a), out_a);
      keep(i, kept.laterEdges(i, lo[si], hi[si], scratch_b, b), out_b);
      ASSERT_EQ(out_a, out_b) << "step " << k << ", edge " << i;
      later_pairs += static_cast<long>(out_a.size());
    }
  }
  std::printf("%ld node-triangle and %ld edge pairs, %ld of %d steps walked the tree\n", pairs,
              later_pairs, kept.builds(), steps);
  EXPECT_EQ(fresh.builds(), steps);
  EXPECT_LT(kept.builds(), steps / 4);  // the point of keeping them
  EXPECT_GT(later_pairs, 0);
}

TEST(SurfacePairCache, AnImpactComesOutTheSameToTheLastBitWithKeptAndWithFreshPairs) {
  // Two blocks as one body, one thrown at the other: every step's candidates (with their
  // normals, gaps and multipliers) and the motion must be those of a fresh search every step.
  int second = 0;
  const TetMesh mesh = twoCubes(0.02, 3, second);
  FemWorld* worlds[2] = {nullptr, nullptr};
  FemBody* bodies[2] = {nullptr, nullptr};
  std::unique_ptr<FemWorld> owned[2];
  for (int run = 0; run < 2; ++run) {
    WorldSettings settings;
    settings.gravity.setZero();
    settings.solver.time_step = 5e-4;
    settings.solver.threads = 2;
    owned[run] = std::make_unique<FemWorld>(settings);
    worlds[run] = owned[run].get();
    bodies[run] = worlds[run]->addBody("blocks", mesh, Material{}).value();
    SelfContactSettings contact;
    contact.search_skin = run == 0 ? 0.0 : 0.25;
    ASSERT_TRUE(bodies[run]->enableSelfContact(contact).ok());
    FemBodyCheckpoint start = bodies[run]->checkpoint();
    for (int i = second; i < mesh.nodeCount(); ++i)
      start.state.velocities.segment<3>(3 * i) = Eigen::Vector3d(-4, 0.5, 0);
    bodies[run]->restore(start);
  }
  int searches = 0, builds = 0, max_active = 0, max_candidates = 0;
  for (int k = 0; k < 150; ++k) {
    for (FemWorld* world : worlds)
      ASSERT_TRUE(world->step().ok);
    const std::vector<SurfaceContact>& a = bodies[0]->selfContact()->contacts();
    const std::vector<SurfaceContact>& b = bodies[1]->selfContact()->contacts();
    ASSERT_EQ(a.size(), b.size()) << "step " << k;
    for (size_t c = 0; c < a.size(); ++c) {
      ASSERT_EQ(a[c].nodes, b[c].nodes) << "step " << k << ", contact " << c;
      ASSERT_EQ(a[c].edge, b[c].edge);
      ASSERT_EQ(a[c].triangle, b[c].triangle);
      ASSERT_EQ(a[c].gap, b[c].gap);
      ASSERT_EQ((a[c].multiplier - b[c].multiplier).cwiseAbs().maxCoeff(), 0.0);
    }
    ASSERT_EQ((bodies[0]->state().positions - bodies[1]->state().positions).cwiseAbs().maxCoeff(),
              0.0)
        << "step " << k;
    const SelfContactStats& s = bodies[1]->selfContact()->stats();
    searches += s.searches;
    builds += s.search_builds;
    max_active = std::max(max_active, s.active);
    max_candidates = std::max(max_candidates, static_cast<int>(a.size()));
  }
  std::printf("%d searches, %d walked the tree; up to %d candidates, %d active\n", searches, builds,
              max_candidates, max_active);
  EXPECT_GT(max_active, 0);         // the blocks met
  EXPECT_LT(builds, searches / 2);  // and most searches reused the kept pairs
}

}  // namespace
}  // namespace torsion
