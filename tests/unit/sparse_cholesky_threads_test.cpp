// The direct solver factorises on the calling thread (solve/serial_openmp.h). Debian's SuiteSparse
// is built with OpenMP, and CHOLMOD's supernodal factorisation opens parallel regions that start a
// pool of OpenMP threads beside the library's own (TORSION_THREADS): they cost most of a
// factorisation on 2 cores, and would run beside the haptic loop.
#include <gtest/gtest.h>

#include <Eigen/SparseCore>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <vector>

#include "torsion/solve/cholmod_solver.h"

namespace torsion {
namespace sparse_cholesky_threads_test {

long threadsOfThisProcess() {
  const std::filesystem::directory_iterator tasks("/proc/self/task");
  return std::distance(begin(tasks), end(tasks));
}

// The lower triangle of the 7-point Laplacian of an n^3 grid plus the identity: symmetric positive
// definite, and its factor has supernodes of hundreds of columns (CHOLMOD's parallel regions open
// only above a size).
Eigen::SparseMatrix<double> gridLaplacian(int n) {
  const auto index = [n](int i, int j, int k) { return (k * n + j) * n + i; };
  std::vector<Eigen::Triplet<double>> entries;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int row = index(i, j, k);
        entries.emplace_back(row, row, 7.0);
        if (i > 0) entries.emplace_back(row, index(i - 1, j, k), -1.0);
        if (j > 0) entries.emplace_back(row, index(i, j - 1, k), -1.0);
        if (k > 0) entries.emplace_back(row, index(i, j, k - 1), -1.0);
      }
  Eigen::SparseMatrix<double> lower(n * n * n, n * n * n);
  lower.setFromTriplets(entries.begin(), entries.end());
  return lower;
}

TEST(SparseCholeskyThreads, AFactorisationAndItsSolvesStartNoThreads) {
  // In a process of its own (the death-test machinery re-runs this test alone), so that no other
  // test has started threads before it.
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        const long before = threadsOfThisProcess();
        const Eigen::SparseMatrix<double> A = gridLaplacian(24);
        SparseCholesky cholesky;
        bool ok = true;
        for (int round = 0; round < 3; ++round)  // the numeric refactorisation too
          ok = ok && cholesky.factorize(A);
        Eigen::VectorXd x;
        cholesky.solve(Eigen::VectorXd::Ones(A.rows()), x);
        const double residual =
            (A.selfadjointView<Eigen::Lower>() * x - Eigen::VectorXd::Ones(A.rows())).norm();
        const long after = threadsOfThisProcess();
        std::exit(ok && residual < 1e-8 && after == before ? 0 : 1);
      },
      ::testing::ExitedWithCode(0), "");
}

}  // namespace sparse_cholesky_threads_test
}  // namespace torsion
