// Random SPD islands with random rows (seeded): every solve converges within the iteration cap
// with its residual below the tolerance, its impulses in the lagged model's disk, and a second
// solve of the same input gives bit-identical output. Each row's lagged normal impulse is its
// normal impulse in a first solve without friction bounds (all lagged impulses 0) times a random
// factor in [0.5, 1.5]: what a previous step of a changing island would hand over.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <random>

#include "sap_test_support.h"

namespace torsion::sap {
namespace {

struct RandomIsland {
  std::vector<std::unique_ptr<IslandBody>> bodies;
  std::vector<ContactRow> rows;
};

// The ranges the islands are drawn from.
struct Spread {
  double min_mass, max_mass;  // kg per node
  double max_spring;          // N/m between chained nodes
  int max_nodes, max_rows, max_terms;
  double max_mu;
  double max_log_stiffness;  // rows' k up to 10^this N/m, from 1e2
  double max_gap;            // m
};
// Everyday islands, and extreme ones: mass ratios of 1e6, springs and contacts up to 1e8 and
// 1e12 N/m, mu up to 2, gaps of +-1 cm.
constexpr Spread kOrdinary{0.01, 2.0, 1e4, 12, 25, 3, 1.2, 7, 1e-3};
constexpr Spread kExtreme{1e-4, 1e2, 1e8, 40, 80, 4, 2.0, 12, 1e-2};

// A sparse SPD matrix over `nodes` nodes: a spring chain's stiffness plus masses, both random.
Eigen::SparseMatrix<double> randomSpd(int nodes, const Spread& spread, std::mt19937& rng) {
  std::uniform_real_distribution<double> mass(spread.min_mass, spread.max_mass),
      spring(1.0, spread.max_spring);
  std::vector<Eigen::Triplet<double>> entries;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int i = 0; i < nodes; ++i) {
    const double m = mass(rng);
    for (int c = 0; c < 3; ++c)
      entries.emplace_back(3 * i + c, 3 * i + c, m);
  }
  for (int i = 0; i + 1 < nodes; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    const Eigen::Matrix3d block = spring(rng) * 1e-4 * d * d.transpose();  // dt^2 k d d^T
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        const double value = block(a, b);
        entries.emplace_back(3 * i + a, 3 * i + b, value);
        entries.emplace_back(3 * i + 3 + a, 3 * i + 3 + b, value);
        entries.emplace_back(3 * i + a, 3 * i + 3 + b, -value);
        entries.emplace_back(3 * i + 3 + a, 3 * i + b, -value);
      }
  }
  Eigen::SparseMatrix<double> a(3 * nodes, 3 * nodes);
  a.setFromTriplets(entries.begin(), entries.end());
  return a;
}

ContactTerm randomTerm(const RandomIsland& island, double sign, const Eigen::Matrix3d& frame,
                       std::mt19937& rng) {
  std::uniform_int_distribution<int> pick_body(0, static_cast<int>(island.bodies.size()) - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), weight(0.05, 1.0);
  const int body = pick_body(rng);
  const IslandBody& b = *island.bodies[static_cast<size_t>(body)];
  if (b.blockSize() == 6)
    return rigidPointTerm(body, 0.2 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)), sign,
                          frame);
  std::uniform_int_distribution<int> pick_node(0, b.dofs() / 3 - 1);
  return nodeTerm(body, pick_node(rng), sign * weight(rng), frame);
}

Eigen::VectorXd randomVector(int size, double scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd x(size);
  for (int i = 0; i < size; ++i)
    x(i) = scale * unit(rng);
  return x;
}

RandomIsland randomIsland(unsigned seed, const Spread& spread) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> nodes(2, spread.max_nodes), row_count(1, spread.max_rows),
      terms(1, spread.max_terms);
  RandomIsland island;
  for (int body = 0; body < 2; ++body) {
    const int n = nodes(rng);
    Eigen::SparseMatrix<double> a = randomSpd(n, spread, rng);
    auto matrix = std::make_unique<MatrixBody>(std::move(a), randomVector(3 * n, 0.1, rng));
    // A few prescribed dofs: a held node component moving at a random speed.
    if (seed % 3 == 0)
      matrix->prescribe(static_cast<int>(seed % static_cast<unsigned>(3 * n)), 0.05 * unit(rng));
    island.bodies.push_back(std::move(matrix));
  }
  const Eigen::Matrix3d inertia = Eigen::Vector3d(0.02, 0.03, 0.05).asDiagonal();
  Eigen::VectorXd twist_momentum(6);
  twist_momentum << unit(rng), unit(rng), unit(rng), 0.01 * unit(rng), 0.01 * unit(rng), 0.0;
  island.bodies.push_back(std::make_unique<RigidBody>(1.5, inertia, twist_momentum));
  const int rows = row_count(rng);
  for (int i = 0; i < rows; ++i) {
    ContactRow row;
    row.frame = contactFrame(Eigen::Vector3d(unit(rng), unit(rng), unit(rng)));
    const int count = terms(rng);
    for (int t = 0; t < count; ++t)
      row.terms.push_back(randomTerm(island, t == 0 ? 1.0 : -1.0, row.frame, rng));
    row.mu = i % 7 == 0 ? 0.0 : 0.5 * spread.max_mu * (unit(rng) + 1);
    row.stiffness = std::pow(10.0, 2 + 0.5 * (spread.max_log_stiffness - 2) * (unit(rng) + 1));
    row.dissipation_time = 0.005 * (unit(rng) + 1);
    row.gap = spread.max_gap * unit(rng);
    island.rows.push_back(row);
  }
  return island;
}

bool bitIdentical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() &&
         std::memcmp(a.data(), b.data(), sizeof(double) * static_cast<size_t>(a.size())) == 0;
}

// Solves islands first_seed .. first_seed + count - 1 and checks each (see the file's comment).
void checkRandomIslands(const Spread& spread, unsigned first_seed, unsigned count, double dt) {
  int worst_newton = 0, worst_cg = 0, total_newton = 0, worst_refine = 0, total_search = 0;
  for (unsigned seed = first_seed; seed < first_seed + count; ++seed) {
    RandomIsland island = randomIsland(seed, spread);
    std::vector<const IslandBody*> bodies;
    for (const auto& body : island.bodies)
      bodies.push_back(body.get());
    SapSolver solver;
    Eigen::VectorXd v;
    SCOPED_TRACE(seed);
    {
      const SapProblem unbounded = SapProblem::create(bodies, island.rows, dt).value();
      const SapReport first = solver.solve(unbounded, v);
      test::expectCoulombAndComplementarity(unbounded, first);
      std::mt19937 rng(seed);
      std::uniform_real_distribution<double> factor(0.5, 1.5);
      for (size_t i = 0; i < island.rows.size(); ++i)
        island.rows[i].lagged_normal_impulse = first.impulses[i](2) * factor(rng);
      v.resize(0);
    }
    const SapProblem problem = SapProblem::create(bodies, island.rows, dt).value();
    const SapReport report = solver.solve(problem, v);
    test::expectCoulombAndComplementarity(problem, report);
    EXPECT_LE(report.newton_iterations, solver.settings().max_newton_iterations);
    worst_newton = std::max(worst_newton, report.newton_iterations);
    worst_cg = std::max(worst_cg, report.cg_iterations);
    total_newton += report.newton_iterations;
    total_search += report.line_search_iterations;
    // The same input again, on a fresh solver and on the used one: the same bits.
    for (int again = 0; again < 2; ++again) {
      SapSolver fresh;
      SapSolver& other = again == 0 ? fresh : solver;
      Eigen::VectorXd w;
      const SapReport repeat = other.solve(problem, w);
      EXPECT_TRUE(bitIdentical(v, w));
      EXPECT_EQ(repeat.newton_iterations, report.newton_iterations);
      EXPECT_EQ(repeat.cg_iterations, report.cg_iterations);
      for (size_t i = 0; i < report.impulses.size(); ++i)
        EXPECT_EQ(
            std::memcmp(repeat.impulses[i].data(), report.impulses[i].data(), 3 * sizeof(double)),
            0);
    }
    // Warm-started from its own answer it is done at once.
    Eigen::VectorXd warm = v;
    const SapReport again = solver.solve(problem, warm);
    EXPECT_TRUE(again.converged);
    EXPECT_EQ(again.newton_iterations, 0);
    // Newton's local convergence: from there, six more digits take a few iterations.
    SapSolverSettings tight;
    tight.relative_tolerance = 1e-12;
    SapSolver tight_solver(tight);
    const SapReport refined = tight_solver.solve(problem, warm);
    EXPECT_TRUE(refined.converged) << refined.message;
    worst_refine = std::max(worst_refine, refined.newton_iterations);
  }
  std::printf(
      "random islands: %d problems, Newton mean %.1f, max %d; CG per solve max %d; line "
      "search %.1f evaluations per Newton step; 1e-6 -> 1e-12 in <= %d\n",
      static_cast<int>(count), static_cast<double>(total_newton) / count, worst_newton, worst_cg,
      static_cast<double>(total_search) / std::max(total_newton, 1), worst_refine);
}

TEST(SapRandom, RandomIslandsConvergeAndRepeatBitForBit) {
  checkRandomIslands(kOrdinary, 1, 60, 1e-2);
}

// Under AddressSanitizer (25 times slower here) the memory checks need a few islands, not the
// statistics: the Release suite solves all 200.
#if defined(__SANITIZE_ADDRESS__) || (defined(__has_feature) && __has_feature(address_sanitizer))
constexpr unsigned kExtremeIslands = 40;
#else
constexpr unsigned kExtremeIslands = 200;
#endif

// Seed 1506 once had a frictionless row at rest with an opening gap stuck at a negative impulse.
TEST(SapRandom, ExtremeIslandsConvergeAndRepeatBitForBit) {
  checkRandomIslands(kExtreme, 1401, kExtremeIslands, 1e-2);
}

// The cap is reported, never passed off as a solution.
TEST(SapRandom, AnIterationCapIsReported) {
  const RandomIsland island = randomIsland(5, kOrdinary);
  std::vector<const IslandBody*> bodies;
  for (const auto& body : island.bodies)
    bodies.push_back(body.get());
  const SapProblem problem = SapProblem::create(bodies, island.rows, 1e-2).value();
  SapSolverSettings settings;
  settings.max_newton_iterations = 1;
  settings.relative_tolerance = 1e-15;
  SapSolver solver(settings);
  Eigen::VectorXd v;
  const SapReport report = solver.solve(problem, v);
  EXPECT_FALSE(report.converged);
  EXPECT_EQ(report.message, "iteration cap");
  EXPECT_GT(report.residual, report.tolerance);
}

// A non-finite input (a NaN momentum from upstream) stops the solve at once, reported.
TEST(SapRandom, ANonFiniteInputIsReported) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  MatrixBody particle(test::massMatrix({1.0}), Eigen::Vector3d(0.0, nan, 0.0));
  ContactRow row;
  row.terms.push_back(nodeTerm(0, 0, 1.0, row.frame));
  row.stiffness = 1e5;
  const SapProblem problem = SapProblem::create({&particle}, {row}, 1e-3).value();
  SapSolver solver;
  Eigen::VectorXd v;
  const SapReport report = solver.solve(problem, v);
  EXPECT_FALSE(report.converged);
  EXPECT_EQ(report.message, "non-finite residual");
  EXPECT_EQ(report.newton_iterations, 0);
}

}  // namespace
}  // namespace torsion::sap
