// The rigid modes of a FEM body's aggregates (coarse_space.h).
#include "torsion/contact/solve/coarse_space.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>

namespace torsion::sap {

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = Eigen::Matrix<double, 6, 1>;

// A mode is kept when its Gram eigenvalue exceeds this fraction of the aggregate's largest: below,
// the held dofs leave it no motion of its own (a rounding direction, not a mode).
constexpr double kModeFloor = 1e-10;

// Splits `nodes` (a range of indices into points) into `count` aggregates numbered from `first`.
void bisect(const std::vector<Eigen::Vector3d>& points, std::vector<int>::iterator begin,
            std::vector<int>::iterator end, int count, int first, std::vector<int>& aggregate_of) {
  if (count <= 1 || end - begin <= 1) {
    for (auto it = begin; it != end; ++it)
      aggregate_of[static_cast<std::size_t>(*it)] = first;
    return;
  }
  Eigen::Vector3d lo = points[static_cast<std::size_t>(*begin)], hi = lo;
  for (auto it = begin; it != end; ++it) {
    lo = lo.cwiseMin(points[static_cast<std::size_t>(*it)]);
    hi = hi.cwiseMax(points[static_cast<std::size_t>(*it)]);
  }
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const int left_count = count / 2;
  const auto size = end - begin;
  const auto middle = begin + size * left_count / count;
  std::nth_element(begin, middle, end, [&](int a, int b) {
    const double pa = points[static_cast<std::size_t>(a)][axis];
    const double pb = points[static_cast<std::size_t>(b)][axis];
    return pa < pb || (pa == pb && a < b);
  });
  bisect(points, begin, middle, left_count, first, aggregate_of);
  bisect(points, middle, end, count - left_count, first + left_count, aggregate_of);
}

}  // namespace

int aggregateCountFor(const std::vector<Eigen::Vector3d>& rest_points) {
  if (rest_points.empty()) return 0;
  Eigen::Vector3d lo = rest_points.front(), hi = lo;
  for (const Eigen::Vector3d& p : rest_points) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Eigen::Vector3d side = hi - lo;
  std::sort(side.data(), side.data() + 3);
  if (!(side[1] > 0)) return 0;                  // a line of nodes: not a solid
  const double slenderness = side[2] / side[1];  // the longest side over the second longest
  if (slenderness < kMinSlenderness) return 0;
  const double count =
      std::max(static_cast<double>(rest_points.size()) / kNodesPerAggregate, slenderness);
  // Rounded up, but a ratio of 12 that rounding made 12.000000001 stays 12.
  return static_cast<int>(std::min(std::ceil(count - 1e-9), double{kMaxAggregates}));
}

std::vector<int> bisectIntoAggregates(const std::vector<Eigen::Vector3d>& points, int count) {
  assert(count >= 1);
  std::vector<int> order(points.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<int> aggregate_of(points.size(), 0);
  // More aggregates than points: one point each, the rest empty.
  count = std::min<int>(count, std::max<int>(1, static_cast<int>(points.size())));
  bisect(points, order.begin(), order.end(), count, 0, aggregate_of);
  return aggregate_of;
}

NodeCoarseSpace::NodeCoarseSpace(const SystemOperator& system, const NodeConstraints& constraints,
                                 const Eigen::VectorXd& positions,
                                 const std::vector<int>& aggregate_of, int aggregate_count) {
  assert(aggregate_of.size() == static_cast<std::size_t>(system.model().nodeCount()));
  aggregate_of_ = aggregate_of;
  aggregate_count_ = aggregate_count;
  update(system, constraints, positions);
}

void NodeCoarseSpace::update(const SystemOperator& system, const NodeConstraints& constraints,
                             const Eigen::VectorXd& positions) {
  assert(positions.size() == 3 * system.model().nodeCount());
  first_column_.assign(1, 0);
  constraints_ = &constraints;
  if (system.model().nodalPressure()) return;
  buildBasis(constraints, positions, aggregate_count_);
  assembleGalerkin(system);
}

void NodeCoarseSpace::buildBasis(const NodeConstraints& constraints,
                                 const Eigen::VectorXd& positions, int aggregate_count) {
  const auto nodes = aggregate_of_.size();
  std::vector<Eigen::Vector3d> centroid(static_cast<std::size_t>(aggregate_count),
                                        Eigen::Vector3d::Zero());
  std::vector<int> members(static_cast<std::size_t>(aggregate_count), 0);
  for (std::size_t n = 0; n < nodes; ++n) {
    centroid[static_cast<std::size_t>(aggregate_of_[n])] +=
        positions.segment<3>(3 * static_cast<Eigen::Index>(n));
    ++members[static_cast<std::size_t>(aggregate_of_[n])];
  }
  // The rigid modes of each node, filtered, and each aggregate's Gram matrix Z_a^T Z_a.
  basis_.resize(nodes);
  offsets_.resize(nodes);
  std::vector<Matrix6d> gram(static_cast<std::size_t>(aggregate_count), Matrix6d::Zero());
  for (std::size_t n = 0; n < nodes; ++n) {
    const auto a = static_cast<std::size_t>(aggregate_of_[n]);
    const Eigen::Vector3d p =
        positions.segment<3>(3 * static_cast<Eigen::Index>(n)) - centroid[a] / members[a];
    offsets_[n] = p;
    NodeBasis& z = basis_[n];
    z.leftCols<3>().setIdentity();
    // omega x p = -[p]x omega: the rotation's columns.
    z.rightCols<3>() << 0, p.z(), -p.y(), -p.z(), 0, p.x(), p.y(), -p.x(), 0;
    if (constraints.isConstrained(static_cast<int>(n)))
      for (int k = 0; k < 6; ++k)
        z.col(k) = constraints.filterNode(static_cast<int>(n), z.col(k));
    gram[a].noalias() += z.transpose() * z;
  }
  // An orthonormal basis of each aggregate's span: V = (eigenvectors / sqrt(eigenvalue)) over the
  // modes above the floor, largest first.
  reduction_.assign(gram.size(), Matrix6d::Zero());
  for (std::size_t a = 0; a < gram.size(); ++a) {
    const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(gram[a]);
    const Eigen::Matrix<double, 6, 1>& values = eigen.eigenvalues();
    int kept = 0;
    for (int k = 5; k >= 0; --k)
      if (values[k] > kModeFloor * values[5] && values[k] > 0) ++kept;
    for (int k = 0; k < kept; ++k)
      reduction_[a].col(k) = eigen.eigenvectors().col(5 - k) / std::sqrt(values[5 - k]);
    first_column_.push_back(first_column_.back() + kept);
  }
  for (std::size_t n = 0; n < nodes; ++n)
    basis_[n] = basis_[n] * reduction_[static_cast<std::size_t>(aggregate_of_[n])];
}

void NodeCoarseSpace::assembleGalerkin(const SystemOperator& system) {
  // A = m_c M + k_c K, K as upper-triangle node blocks (K(c, n) = K(n, c)^T): per block row n of
  // aggregate a, T_b = sum over its off-diagonal blocks with c in aggregate b of A_nc B_c, then
  // E_ab += B_n^T T_b and E_ba += (B_n^T T_b)^T; the diagonal block once. Summed per aggregate pair
  // in fixed 6 x 6 blocks, reduced to the aggregates' columns at the end.
  const std::vector<int>& row_offsets = system.blockRowOffsets();
  const std::vector<int>& block_columns = system.blockColumns();
  const std::vector<Eigen::Matrix3d>& blocks = system.stiffnessBlocks();
  const std::vector<double>& masses = system.model().nodeMasses();
  const double mass_coefficient = system.massCoefficient();
  const double stiffness_coefficient = system.stiffnessCoefficient();
  const auto aggregates = static_cast<int>(reduction_.size());
  std::vector<Matrix6d>& sums = galerkin_sums_;
  sums.assign(static_cast<std::size_t>(aggregates * aggregates), Matrix6d::Zero());
  const auto sum = [&](int a, int b) -> Matrix6d& {
    return sums[static_cast<std::size_t>(a * aggregates + b)];
  };
  // The row's aggregates other than its own and their T_b (a row touches few).
  std::vector<int> touched;
  std::vector<Eigen::Matrix<double, 3, 6>> partial;
  for (std::size_t n = 0; n < aggregate_of_.size(); ++n) {
    const int a = aggregate_of_[n];
    const NodeBasis& bn = basis_[n];
    Eigen::Matrix<double, 3, 6> own = (mass_coefficient * masses[n]) * bn;
    Eigen::Matrix<double, 3, 6> own_off = Eigen::Matrix<double, 3, 6>::Zero();
    touched.clear();
    partial.clear();
    for (int s = row_offsets[n]; s < row_offsets[n + 1]; ++s) {
      const auto c = static_cast<std::size_t>(block_columns[static_cast<std::size_t>(s)]);
      const Eigen::Matrix3d& k = blocks[static_cast<std::size_t>(s)];
      if (c == n) {
        own.noalias() += stiffness_coefficient * (k * bn);
        continue;
      }
      const int b = aggregate_of_[c];
      if (b == a) {
        own_off.noalias() += k * basis_[c];
        continue;
      }
      const auto at = std::find(touched.begin(), touched.end(), b);
      if (at == touched.end()) {
        touched.push_back(b);
        partial.emplace_back(k * basis_[c]);
      } else {
        partial[static_cast<std::size_t>(at - touched.begin())].noalias() += k * basis_[c];
      }
    }
    const Matrix6d same = stiffness_coefficient * (bn.transpose() * own_off);
    sum(a, a).noalias() += bn.transpose() * own + same + same.transpose();
    for (std::size_t t = 0; t < touched.size(); ++t) {
      const Matrix6d m = stiffness_coefficient * (bn.transpose() * partial[t]);
      sum(a, touched[t]) += m;
      sum(touched[t], a) += m.transpose();
    }
  }
  galerkin_.setZero(dofs(), dofs());
  for (int a = 0; a < aggregates; ++a)
    for (int b = 0; b < aggregates; ++b)
      galerkin_.block(firstColumn(a), firstColumn(b), columns(a), columns(b)) =
          sum(a, b).topLeftCorner(columns(a), columns(b));
}

void NodeCoarseSpace::restrictTo(const Eigen::Ref<const Eigen::VectorXd>& x,
                                 Eigen::Ref<Eigen::VectorXd> out) const {
  // Z_n^T x_n = V_a^T [S_n x_n; p_n x S_n x_n]: each aggregate's force and moment about its
  // centroid, then its reduction V_a.
  moments_.assign(reduction_.size(), Vector6d::Zero());
  for (std::size_t n = 0; n < aggregate_of_.size(); ++n) {
    Eigen::Vector3d f = x.segment<3>(3 * static_cast<Eigen::Index>(n));
    if (constraints_->isConstrained(static_cast<int>(n)))
      f = constraints_->filterNode(static_cast<int>(n), f);
    Vector6d& m = moments_[static_cast<std::size_t>(aggregate_of_[n])];
    m.head<3>() += f;
    m.tail<3>() += offsets_[n].cross(f);
  }
  for (std::size_t a = 0; a < reduction_.size(); ++a) {
    const int k = columns(static_cast<int>(a));
    out.segment(firstColumn(static_cast<int>(a)), k).noalias() =
        reduction_[a].leftCols(k).transpose() * moments_[a];
  }
}

void NodeCoarseSpace::prolongAdd(const Eigen::Ref<const Eigen::VectorXd>& y,
                                 Eigen::Ref<Eigen::VectorXd> x) const {
  // Z_n y_a = S_n (t + omega x p_n), (t; omega) = V_a y_a: each aggregate's rigid motion.
  moments_.resize(reduction_.size());
  for (std::size_t a = 0; a < reduction_.size(); ++a) {
    const int k = columns(static_cast<int>(a));
    moments_[a].noalias() =
        reduction_[a].leftCols(k) * y.segment(firstColumn(static_cast<int>(a)), k);
  }
  for (std::size_t n = 0; n < aggregate_of_.size(); ++n) {
    const Vector6d& m = moments_[static_cast<std::size_t>(aggregate_of_[n])];
    Eigen::Vector3d u = m.head<3>() + m.tail<3>().cross(offsets_[n]);
    if (constraints_->isConstrained(static_cast<int>(n)))
      u = constraints_->filterNode(static_cast<int>(n), u);
    x.segment<3>(3 * static_cast<Eigen::Index>(n)) += u;
  }
}

}  // namespace torsion::sap
