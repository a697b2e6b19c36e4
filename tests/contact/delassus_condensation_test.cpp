// The soft side of the Delassus operator (delassus_condensation.h), W_soft = U^T A^-1 U from the
// sparse factor, against the same product from a dense solve: on a 3-D grid's stiffness-like
// matrix (an elimination tree with real branches), for node rows and face rows, for numbers of
// contact rows that fill the groups of four or not, a contact row twice, components a
// prescription filters out, no contact row at all, and a factor without a fill-reducing
// permutation. Only products with a zero factor are skipped, so the two agree to rounding.
#include "torsion/contact/delassus_condensation.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <random>
#include <vector>

namespace torsion {
namespace {

double uniform(std::mt19937& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng()) / 4294967296.0;
}

// A symmetric positive definite matrix with a 3-D grid's pattern, 3 unknowns per node: coupled
// 3x3 blocks between neighbours (a stiffness), plus a mass on the diagonal.
Eigen::SparseMatrix<double> gridMatrix(int nx, int ny, int nz, std::mt19937& rng) {
  const int nodes = nx * ny * nz;
  auto id = [&](int i, int j, int k) { return (k * ny + j) * nx + i; };
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(3 * nodes, 3 * nodes);
  for (int k = 0; k < nz; ++k) {
    for (int j = 0; j < ny; ++j) {
      for (int i = 0; i < nx; ++i) {
        const int a = id(i, j, k);
        const int neighbours[3] = {i + 1 < nx ? id(i + 1, j, k) : -1,
                                   j + 1 < ny ? id(i, j + 1, k) : -1,
                                   k + 1 < nz ? id(i, j, k + 1) : -1};
        for (int b : neighbours) {
          if (b < 0) continue;
          Eigen::Matrix3d g;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c)
              g(r, c) = uniform(rng, -1, 1);
          const Eigen::Matrix3d spring = g * g.transpose() + Eigen::Matrix3d::Identity();
          dense.block<3, 3>(3 * a, 3 * a) += spring;
          dense.block<3, 3>(3 * b, 3 * b) += spring;
          dense.block<3, 3>(3 * a, 3 * b) -= spring;
          dense.block<3, 3>(3 * b, 3 * a) -= spring;
        }
        dense.block<3, 3>(3 * a, 3 * a) += 0.01 * Eigen::Matrix3d::Identity();
      }
    }
  }
  return dense.sparseView();
}

struct Row {
  std::vector<int> nodes;
  std::vector<double> weights;
  std::vector<int> free_axes;  // the components a prescription leaves free (node rows)
};

// U (3n x 3m): column 3s + a is row s's unit impulse along axis a, spread by the weights.
Eigen::SparseMatrix<double> unitImpulses(int nodes, const std::vector<Row>& rows) {
  std::vector<Eigen::Triplet<double>> entries;
  for (size_t s = 0; s < rows.size(); ++s) {
    for (size_t q = 0; q < rows[s].nodes.size(); ++q) {
      for (int axis : rows[s].free_axes)
        entries.emplace_back(3 * rows[s].nodes[q] + axis, 3 * static_cast<int>(s) + axis,
                             rows[s].weights[q]);
    }
  }
  Eigen::SparseMatrix<double> u(3 * nodes, 3 * static_cast<Eigen::Index>(rows.size()));
  u.setFromTriplets(entries.begin(), entries.end());
  return u;
}

std::vector<Row> randomRows(int nodes, int count, std::mt19937& rng) {
  std::vector<Row> rows;
  for (int s = 0; s < count; ++s) {
    Row row;
    if (s % 3 == 2) {  // a face point: three nodes, barycentric weights
      const double w0 = uniform(rng, 0.1, 0.5), w1 = uniform(rng, 0.1, 0.4);
      row.weights = {w0, w1, 1 - w0 - w1};
      for (int q = 0; q < 3; ++q)
        row.nodes.push_back(static_cast<int>(rng() % static_cast<unsigned>(nodes)));
      row.free_axes = {0, 1, 2};
    } else {
      row.nodes = {static_cast<int>(rng() % static_cast<unsigned>(nodes))};
      row.weights = {1};
      row.free_axes = s % 5 == 4 ? std::vector<int>{0, 2} : std::vector<int>{0, 1, 2};
    }
    rows.push_back(row);
  }
  return rows;
}

template <typename Factor>
Eigen::MatrixXd condensed(const Eigen::SparseMatrix<double>& a,
                          const Eigen::SparseMatrix<double>& u) {
  Factor factor(a);
  EXPECT_EQ(factor.info(), Eigen::Success);
  DelassusCondensation condensation;
  Eigen::MatrixXd w;
  condensation.lowerGram(factor.matrixL().nestedExpression(), factor.permutationP().indices(), u,
                         w);
  return w;
}

Eigen::MatrixXd reference(const Eigen::SparseMatrix<double>& a,
                          const Eigen::SparseMatrix<double>& u) {
  const Eigen::MatrixXd du(u);
  return du.transpose() * Eigen::MatrixXd(a).llt().solve(du);
}

void expectLowerEqual(const Eigen::MatrixXd& w, const Eigen::MatrixXd& expected) {
  ASSERT_EQ(w.rows(), expected.rows());
  ASSERT_EQ(w.cols(), expected.cols());
  const double scale = expected.cwiseAbs().maxCoeff();
  for (Eigen::Index j = 0; j < w.cols(); ++j) {
    for (Eigen::Index i = 0; i < w.rows(); ++i) {
      if (i >= j) {
        EXPECT_NEAR(w(i, j), expected(i, j), 1e-10 * scale) << "entry " << i << ", " << j;
      } else {
        EXPECT_EQ(w(i, j), 0.0) << "the strict upper part stays zero: " << i << ", " << j;
      }
    }
  }
}

using AmdFactor = Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower>;
using NaturalFactor =
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower, Eigen::NaturalOrdering<int>>;

TEST(DelassusCondensation, EqualsTheDenseProductForAnyNumberOfRows) {
  std::mt19937 rng(7);
  const Eigen::SparseMatrix<double> a = gridMatrix(7, 6, 5, rng);
  const int nodes = 7 * 6 * 5;
  for (int count : {1, 3, 4, 5, 8, 13, 61}) {
    SCOPED_TRACE(count);
    const Eigen::SparseMatrix<double> u = unitImpulses(nodes, randomRows(nodes, count, rng));
    expectLowerEqual(condensed<AmdFactor>(a, u), reference(a, u));
  }
}

TEST(DelassusCondensation, ARowTwiceGivesTwoEqualRowsAndColumns) {
  std::mt19937 rng(11);
  const Eigen::SparseMatrix<double> a = gridMatrix(5, 5, 5, rng);
  std::vector<Row> rows = randomRows(125, 6, rng);
  rows.push_back(rows[1]);
  const Eigen::SparseMatrix<double> u = unitImpulses(125, rows);
  const Eigen::MatrixXd w = condensed<AmdFactor>(a, u);
  expectLowerEqual(w, reference(a, u));
  const Eigen::MatrixXd full = w.selfadjointView<Eigen::Lower>();
  EXPECT_LT((full.block(3, 0, 3, 21) - full.block(18, 0, 3, 21)).cwiseAbs().maxCoeff(),
            1e-12 * full.cwiseAbs().maxCoeff());
}

TEST(DelassusCondensation, WorksWithoutAFillReducingPermutation) {
  std::mt19937 rng(3);
  const Eigen::SparseMatrix<double> a = gridMatrix(4, 4, 6, rng);
  const Eigen::SparseMatrix<double> u = unitImpulses(96, randomRows(96, 9, rng));
  expectLowerEqual(condensed<NaturalFactor>(a, u), reference(a, u));
}

TEST(DelassusCondensation, NoRowsGiveAnEmptyOperator) {
  std::mt19937 rng(5);
  const Eigen::SparseMatrix<double> a = gridMatrix(3, 3, 3, rng);
  const Eigen::SparseMatrix<double> u(81, 0);
  const Eigen::MatrixXd w = condensed<AmdFactor>(a, u);
  EXPECT_EQ(w.rows(), 0);
  EXPECT_EQ(w.cols(), 0);
}

TEST(DelassusCondensation, ReusedForASecondProblemOfAnotherSize) {
  // The workspace (panels, work block) is kept between calls: a smaller problem after a larger
  // one must not see the larger one's values.
  std::mt19937 rng(19);
  const Eigen::SparseMatrix<double> a = gridMatrix(6, 5, 4, rng);
  AmdFactor factor(a);
  DelassusCondensation condensation;
  Eigen::MatrixXd w;
  for (int count : {40, 6, 17}) {
    SCOPED_TRACE(count);
    const Eigen::SparseMatrix<double> u = unitImpulses(120, randomRows(120, count, rng));
    condensation.lowerGram(factor.matrixL().nestedExpression(), factor.permutationP().indices(), u,
                           w);
    expectLowerEqual(w, reference(a, u));
  }
}

}  // namespace
}  // namespace torsion
