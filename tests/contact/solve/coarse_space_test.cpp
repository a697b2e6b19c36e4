// The coarse space of a FEM body (coarse_space.h), checked against its definition with dense
// matrices: aggregates are balanced slices of a long bar; Z's columns are orthonormal, free of the
// held dofs and span exactly each aggregate's filtered rigid modes; restrictTo is Z^T; the
// Galerkin matrix is Z^T A Z of the operator's own product, on a bent bar with held, carried and
// sliding nodes.
#include "torsion/contact/solve/coarse_space.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <memory>
#include <vector>

#include "sap_test_support.h"
#include "torsion/solve/parallel.h"

namespace torsion::sap {
namespace {

TEST(CoarseSpace, AggregatesAreBalancedSlicesOfALongBar) {
  const std::shared_ptr<const FemModel> model = test::slenderBarModel(40);
  const std::vector<Eigen::Vector3d>& points = model->mesh().restPositions();
  for (int count : {1, 3, 8, 13}) {
    const std::vector<int> aggregate = bisectIntoAggregates(points, count);
    std::vector<int> size(static_cast<size_t>(count), 0);
    std::vector<double> lo(size.size(), 1e9), hi(size.size(), -1e9);
    for (size_t n = 0; n < points.size(); ++n) {
      const auto a = static_cast<size_t>(aggregate[n]);
      ASSERT_LT(a, size.size());
      ++size[a];
      lo[a] = std::min(lo[a], points[n].x());
      hi[a] = std::max(hi[a], points[n].x());
    }
    // Nearly equal: a bisection at the counts' ratio leaves at most one node of difference per
    // level.
    const auto [smallest, largest] = std::minmax_element(size.begin(), size.end());
    EXPECT_LE(*largest - *smallest, 4) << count << " aggregates";
    EXPECT_GT(*smallest, 0);
    // Slices: ordered by where they start, no aggregate reaches into the next one's span.
    std::vector<size_t> order(size.size());
    for (size_t a = 0; a < order.size(); ++a)
      order[a] = a;
    std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return lo[a] < lo[b]; });
    for (size_t k = 0; k + 1 < order.size(); ++k)
      EXPECT_LE(hi[order[k]], lo[order[k + 1]]) << count << " aggregates";
  }
  // The count: one slice per thickness of a slender bar (40 cells long, 1 thick; 12 long), one
  // aggregate per kNodesPerAggregate nodes of a long box with many nodes, at most kMaxAggregates;
  // none for a body less slender than kMinSlenderness (a bar of 6, a cube, a plate).
  EXPECT_EQ(aggregateCountFor(points), 32);
  EXPECT_EQ(aggregateCountFor(test::slenderBarModel(12)->mesh().restPositions()), 12);
  EXPECT_EQ(aggregateCountFor(test::slenderBarModel(6)->mesh().restPositions()), 0);
  std::vector<Eigen::Vector3d> rod, cube, plate;
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 5; ++j)
      for (int k = 0; k < 5; ++k)
        rod.emplace_back(i, j, k);  // 39 x 4 x 4: slenderness 9.75, 1000 nodes
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      for (int k = 0; k < 10; ++k) {
        cube.emplace_back(i, j, k);
        plate.emplace_back(i, j, 0.01 * k);
      }
  EXPECT_EQ(aggregateCountFor(rod), (1000 + kNodesPerAggregate - 1) / kNodesPerAggregate);
  EXPECT_EQ(aggregateCountFor(cube), 0);
  EXPECT_EQ(aggregateCountFor(plate), 0);
  EXPECT_EQ(aggregateCountFor({Eigen::Vector3d::Zero()}), 0);
}

// Z as a dense matrix: prolongAdd of each unit coarse vector.
Eigen::MatrixXd denseBasis(const NodeCoarseSpace& space, int nodes) {
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(3 * nodes, space.dofs());
  for (int c = 0; c < space.dofs(); ++c) {
    Eigen::VectorXd column = Eigen::VectorXd::Zero(3 * nodes);
    space.prolongAdd(Eigen::VectorXd::Unit(space.dofs(), c), column);
    z.col(c) = column;
  }
  return z;
}

TEST(CoarseSpace, IsTheFilteredRigidModesOfEachAggregateWithTheirGalerkinSystem) {
  const std::shared_ptr<const FemModel> model = test::slenderBarModel(24);
  const int n = model->nodeCount();
  constexpr int kAggregates = 6;
  Parallel parallel(1);
  SystemOperator system(model, parallel);
  const double dt = 2e-3;
  system.setCoefficients(1.0, dt * dt + dt * model->material().stiffness_damping);
  // The bar bent into a quarter circle (the modes follow the current shape), each element
  // rotated with it, so K is the corotated stiffness of a bent bar.
  const std::vector<Eigen::Vector3d>& rest = model->mesh().restPositions();
  const double radius = 0.5;
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = rest[static_cast<size_t>(i)];
    const double angle = p.x() / radius;
    x.segment<3>(3 * i) << (radius + p.z()) * std::sin(angle), p.y(),
        radius - (radius + p.z()) * std::cos(angle);
  }
  std::vector<Eigen::Matrix3d>& rotations = system.mutableRotations();
  for (int e = 0; e < model->elementCount(); ++e) {
    double mean_x = 0;
    for (int a = 0; a < 4; ++a)
      mean_x +=
          rest[static_cast<size_t>(model->elementNodes()[static_cast<size_t>(4 * e + a)])].x();
    rotations[static_cast<size_t>(e)] =
        Eigen::AngleAxisd(-mean_x / 4 / radius, Eigen::Vector3d::UnitY()).toRotationMatrix();
  }
  // Held: the first aggregate whole (it brings no mode); carried: one node of the last; sliding
  // along x: every node of the third.
  const std::vector<int> aggregate = bisectIntoAggregates(rest, kAggregates);
  const int held = aggregate[0];
  const int last = aggregate[static_cast<size_t>(n - 1)];
  const int sliding = (held + 2) % kAggregates;
  NodeConstraints constraints(n);
  for (int i = 0; i < n; ++i) {
    const int a = aggregate[static_cast<size_t>(i)];
    if (a == held) constraints.prescribeVelocity(i, Eigen::Vector3d::Zero());
    if (a == sliding) constraints.prescribeDirection(i, Eigen::Vector3d::UnitX(), 0.1);
  }
  constraints.prescribeVelocity(n - 1, Eigen::Vector3d(0, 0, 0.2));
  const NodeCoarseSpace space(system, constraints, x, aggregate, kAggregates);

  EXPECT_EQ(space.columns(held), 0);
  EXPECT_EQ(space.columns(last), 6);
  const Eigen::MatrixXd z = denseBasis(space, n);
  // Orthonormal, and held components are zero.
  EXPECT_LT((z.transpose() * z - Eigen::MatrixXd::Identity(z.cols(), z.cols())).norm(), 1e-10);
  for (int c = 0; c < z.cols(); ++c) {
    Eigen::VectorXd filtered = z.col(c);
    constraints.filter(filtered);
    EXPECT_LT((filtered - z.col(c)).norm(), 1e-12);
  }
  // Each aggregate's filtered rigid modes lie in the span (Z Z^T keeps them), and the span has
  // exactly their rank.
  for (int a = 0; a < kAggregates; ++a) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    int members = 0;
    for (int i = 0; i < n; ++i)
      if (aggregate[static_cast<size_t>(i)] == a) {
        centroid += x.segment<3>(3 * i);
        ++members;
      }
    centroid /= members;
    Eigen::MatrixXd modes = Eigen::MatrixXd::Zero(3 * n, 6);
    for (int i = 0; i < n; ++i) {
      if (aggregate[static_cast<size_t>(i)] != a) continue;
      const Eigen::Vector3d p = x.segment<3>(3 * i) - centroid;
      for (int k = 0; k < 3; ++k) {
        modes(3 * i + k, k) = 1;
        modes.block<3, 1>(3 * i, 3 + k) = Eigen::Vector3d::Unit(k).cross(p);
      }
    }
    for (int k = 0; k < 6; ++k) {
      Eigen::VectorXd mode = modes.col(k);
      constraints.filter(mode);
      modes.col(k) = mode;
    }
    EXPECT_LE((z * (z.transpose() * modes) - modes).norm(), 1e-10 * modes.norm()) << a;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(modes);
    svd.setThreshold(1e-8);
    EXPECT_EQ(space.columns(a), svd.rank()) << a;
  }
  // restrictTo is Z^T.
  const Eigen::VectorXd r = Eigen::VectorXd::LinSpaced(3 * n, -1.0, 2.0);
  Eigen::VectorXd restricted(space.dofs());
  space.restrictTo(r, restricted);
  EXPECT_LT((restricted - z.transpose() * r).norm(), 1e-12 * r.norm() * std::sqrt(z.cols()));
  // The Galerkin system: Z^T A Z with A from the operator's product.
  Eigen::MatrixXd az(3 * n, z.cols());
  Eigen::VectorXd column;
  for (int c = 0; c < z.cols(); ++c) {
    system.multiply(z.col(c), column);
    az.col(c) = column;
  }
  const Eigen::MatrixXd expected = z.transpose() * az;
  EXPECT_LT((space.galerkin() - expected).norm(), 1e-12 * expected.norm());
}

TEST(CoarseSpace, UpdatedAtAnotherShapeAndConstraintsItIsTheSpaceBuiltThere) {
  // A FEM body keeps its coarse space from step to step and updates it (the same aggregates, of
  // the rest shape): it must be, to the last bit, the space built afresh at the new step.
  const std::shared_ptr<const FemModel> model = test::slenderBarModel(24);
  const int n = model->nodeCount();
  constexpr int kAggregates = 6;
  Parallel parallel(1);
  SystemOperator system(model, parallel);
  system.setCoefficients(1.0, 4e-6);
  const std::vector<Eigen::Vector3d>& rest = model->mesh().restPositions();
  const std::vector<int> aggregate = bisectIntoAggregates(rest, kAggregates);
  Eigen::VectorXd straight(3 * n), sheared(3 * n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = rest[static_cast<size_t>(i)];
    straight.segment<3>(3 * i) = p;
    sheared.segment<3>(3 * i) = p + Eigen::Vector3d(0, 0.1 * p.x() * p.x(), 0.05 * p.x());
  }
  const NodeConstraints free_nodes(n);
  NodeConstraints held(n);
  for (int i = 0; i < n; ++i)
    if (aggregate[static_cast<size_t>(i)] == aggregate[0])
      held.prescribeVelocity(i, Eigen::Vector3d::Zero());

  NodeCoarseSpace kept(system, free_nodes, straight, aggregate, kAggregates);
  const Eigen::MatrixXd before = denseBasis(kept, n);
  kept.update(system, held, sheared);
  const NodeCoarseSpace built(system, held, sheared, aggregate, kAggregates);
  ASSERT_EQ(kept.dofs(), built.dofs());
  EXPECT_LT(kept.dofs(), before.cols());  // the held aggregate lost its modes
  EXPECT_EQ(kept.galerkin(), built.galerkin());
  EXPECT_EQ(denseBasis(kept, n), denseBasis(built, n));
}

}  // namespace
}  // namespace torsion::sap
