#include "torsion/solve/two_level_preconditioner.h"

#include <algorithm>
#include <cmath>

#include "constrained_blocks.h"
#include "torsion/mesh/quadratic_tet_mesh.h"
#include "torsion/solve/cholmod_solver.h"

namespace torsion {

namespace {

// The corner parents of a fine node and their interpolation weights: itself (1) for a corner,
// its edge's two corners (1/2 each) for a mid-edge node.
struct Parents {
  int count;
  std::array<int, 2> node;
  std::array<double, 2> weight;
};

}  // namespace

TwoLevelPreconditioner::TwoLevelPreconditioner() : factor_(std::make_unique<SparseCholesky>()) {}
TwoLevelPreconditioner::~TwoLevelPreconditioner() = default;

// One pass over the coarse pattern's three index sets, kept together.
// NOLINTNEXTLINE(readability-function-size)
void TwoLevelPreconditioner::buildPattern(const SystemOperator& op) {
  const FemModel& model = op.model();
  fine_nodes_ = model.nodeCount();
  coarse_nodes_ = model.linearMeshPtr()->nodeCount();  // corners keep their indices
  edge_corners_.assign(static_cast<size_t>(fine_nodes_ - coarse_nodes_), {-1, -1});
  const std::vector<int>& element_nodes = model.elementNodes();
  for (int e = 0; e < model.elementCount(); ++e) {
    const int* nodes = element_nodes.data() + 10 * e;
    for (int k = 0; k < 6; ++k) {
      const int mid = nodes[4 + k];
      edge_corners_[static_cast<size_t>(mid - coarse_nodes_)] = {
          nodes[kTet10Edges[static_cast<size_t>(k)][0]],
          nodes[kTet10Edges[static_cast<size_t>(k)][1]]};
    }
  }
  auto parents = [&](int node) {
    if (node < coarse_nodes_) return Parents{1, {node, -1}, {1.0, 0.0}};
    const std::array<int, 2>& c = edge_corners_[static_cast<size_t>(node - coarse_nodes_)];
    return Parents{2, {c[0], c[1]}, {0.5, 0.5}};
  };

  // Directed contributions of each fine slot (row n, column j >= n) that land in the lower
  // triangle: A(n, j) = B adds w_I w_J B to Ac(I, J); for j != n, A(j, n) = B^T adds
  // w_I w_J B^T to Ac(J, I). Upper-triangle targets are skipped (their mirror is counted).
  struct Directed {
    int slot, row, col;
    double weight;
    bool transpose;
  };
  std::vector<Directed> directed;
  const std::vector<int>& row_offsets = op.blockRowOffsets();
  const std::vector<int>& columns = op.blockColumns();
  for (int n = 0; n < fine_nodes_; ++n) {
    const Parents pn = parents(n);
    for (int s = row_offsets[static_cast<size_t>(n)]; s < row_offsets[static_cast<size_t>(n) + 1];
         ++s) {
      const int j = columns[static_cast<size_t>(s)];
      const Parents pj = parents(j);
      for (int a = 0; a < pn.count; ++a) {
        for (int b = 0; b < pj.count; ++b) {
          const int I = pn.node[static_cast<size_t>(a)], J = pj.node[static_cast<size_t>(b)];
          const double w = pn.weight[static_cast<size_t>(a)] * pj.weight[static_cast<size_t>(b)];
          if (I >= J) directed.push_back({s, I, J, w, false});
          if (j != n && J >= I) directed.push_back({s, J, I, w, true});
        }
      }
    }
  }
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(directed.size());
  for (const Directed& d : directed)
    pairs.emplace_back(d.row, d.col);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  coarse_blocks_ = pairs;

  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(pairs.size() * 9);
  for (const auto& [i, j] : pairs) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        if (i == j && r < c) continue;
        triplets.emplace_back(3 * i + r, 3 * j + c, 0.0);
      }
    }
  }
  coarse_.resize(3 * coarse_nodes_, 3 * coarse_nodes_);
  coarse_.setFromTriplets(triplets.begin(), triplets.end());
  coarse_.makeCompressed();
  auto value_index = [&](int row, int col) -> int {
    const int* outer = coarse_.outerIndexPtr();
    const int* inner = coarse_.innerIndexPtr();
    const int* first = inner + outer[col];
    const int* last = inner + outer[col + 1];
    const int* it = std::lower_bound(first, last, row);
    return (it != last && *it == row) ? static_cast<int>(it - inner) : -1;
  };
  coarse_values_.resize(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        coarse_values_[k][static_cast<size_t>(3 * r + c)] =
            value_index(3 * pairs[k].first + r, 3 * pairs[k].second + c);
    }
  }

  // Group the contributions by slot (directed is in slot order already).
  slot_offsets_.assign(columns.size() + 1, 0);
  contributions_.clear();
  contributions_.reserve(directed.size());
  size_t d = 0;
  for (size_t s = 0; s < columns.size(); ++s) {
    slot_offsets_[s] = static_cast<int>(contributions_.size());
    for (; d < directed.size() && directed[d].slot == static_cast<int>(s); ++d) {
      const int block =
          static_cast<int>(std::lower_bound(pairs.begin(), pairs.end(),
                                            std::make_pair(directed[d].row, directed[d].col)) -
                           pairs.begin());
      contributions_.push_back({block, directed[d].weight, directed[d].transpose});
    }
  }
  slot_offsets_[columns.size()] = static_cast<int>(contributions_.size());
}

void TwoLevelPreconditioner::assembleCoarse(const SystemOperator& op,
                                            const NodeConstraints& constraints) {
  double* values = coarse_.valuePtr();
  std::fill(values, values + coarse_.nonZeros(), 0.0);
  auto add_block = [&](int block, const Eigen::Matrix3d& value) {
    const std::array<int, 9>& idx = coarse_values_[static_cast<size_t>(block)];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        const int k = idx[static_cast<size_t>(3 * r + c)];
        if (k >= 0) values[k] += value(r, c);
      }
    }
  };
  const std::vector<Eigen::Matrix3d>& stiffness = op.stiffnessBlocks();
  const std::vector<int>& row_offsets = op.blockRowOffsets();
  const std::vector<double>& mass = op.model().nodeMasses();
  const double c = op.stiffnessCoefficient();
  int row = 0;
  for (size_t s = 0; s < stiffness.size(); ++s) {
    while (row_offsets[static_cast<size_t>(row) + 1] <= static_cast<int>(s))
      ++row;
    Eigen::Matrix3d B = c * stiffness[s];
    if (static_cast<int>(s) == row_offsets[static_cast<size_t>(row)])  // the diagonal block
      B.diagonal().array() += op.massCoefficient() * mass[static_cast<size_t>(row)];
    for (int k = slot_offsets_[s]; k < slot_offsets_[s + 1]; ++k) {
      const Contribution& to = contributions_[static_cast<size_t>(k)];
      add_block(to.block, to.transpose ? Eigen::Matrix3d(to.weight * B.transpose())
                                       : Eigen::Matrix3d(to.weight * B));
    }
  }
  // The corner nodes' constraints: S A S + (I - S), block by block.
  detail::applyConstraintsToBlocks(constraints, coarse_blocks_, coarse_values_, values);
}

void TwoLevelPreconditioner::smooth(const NodeConstraints& constraints,
                                    const std::vector<Eigen::Matrix3d>& block_inverse,
                                    const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  z.resize(r.size());
  for (int i = 0; i < fine_nodes_; ++i) {
    const Eigen::Vector3d zi = block_inverse[static_cast<size_t>(i)] * r.segment<3>(3 * i);
    z.segment<3>(3 * i) = constraints.isConstrained(i) ? constraints.filterNode(i, zi) : zi;
  }
}

void TwoLevelPreconditioner::estimateWeight(const SystemOperator& op,
                                            const NodeConstraints& constraints,
                                            const std::vector<Eigen::Matrix3d>& block_inverse) {
  // Power iterations on D^-1 A (similar to the symmetric D^-1/2 A D^-1/2: real, positive
  // eigenvalues) from a fixed start, so the weight is the same for any thread count.
  Eigen::VectorXd x = Eigen::VectorXd::Ones(3 * fine_nodes_);
  for (int i = 0; i < fine_nodes_; ++i)
    x.segment<3>(3 * i) *= 1.0 + 0.37 * std::sin(i);
  constraints.filter(x);
  double rho = 1;
  for (int k = 0; k < 12; ++k) {
    const double norm = x.norm();
    if (!(norm > 0)) break;
    x /= norm;
    op.multiply(x, product_);
    constraints.filter(product_);
    smooth(constraints, block_inverse, product_, x);
    rho = x.norm();
  }
  // Power iterations approach rho from below: 10 % margin.
  weight_ = 4.0 / (3.0 * 1.1 * std::max(rho, 1.0));
}

bool TwoLevelPreconditioner::prepare(const SystemOperator& op, const NodeConstraints& constraints,
                                     const SolverSettings& settings,
                                     const std::vector<Eigen::Matrix3d>& block_inverse) {
  if (op.model().nodeCount() != fine_nodes_ ||
      static_cast<size_t>(op.blockColumns().size()) + 1 != slot_offsets_.size()) {
    buildPattern(op);
    policy_.invalidate();
  }
  if (!policy_.due(settings)) return true;
  assembleCoarse(op, constraints);
  if (!factor_->factorize(coarse_)) {
    policy_.invalidate();
    return false;
  }
  estimateWeight(op, constraints, block_inverse);
  policy_.factorised();
  return true;
}

void TwoLevelPreconditioner::restrictToCorners(const Eigen::VectorXd& fine,
                                               Eigen::VectorXd& coarse) const {
  coarse = fine.head(3 * coarse_nodes_);
  for (int m = coarse_nodes_; m < fine_nodes_; ++m) {
    const std::array<int, 2>& c = edge_corners_[static_cast<size_t>(m - coarse_nodes_)];
    const Eigen::Vector3d half = 0.5 * fine.segment<3>(3 * m);
    coarse.segment<3>(3 * c[0]) += half;
    coarse.segment<3>(3 * c[1]) += half;
  }
}

void TwoLevelPreconditioner::prolongAdd(const Eigen::VectorXd& coarse,
                                        Eigen::VectorXd& fine) const {
  fine.head(3 * coarse_nodes_) += coarse;
  for (int m = coarse_nodes_; m < fine_nodes_; ++m) {
    const std::array<int, 2>& c = edge_corners_[static_cast<size_t>(m - coarse_nodes_)];
    fine.segment<3>(3 * m) += 0.5 * (coarse.segment<3>(3 * c[0]) + coarse.segment<3>(3 * c[1]));
  }
}

void TwoLevelPreconditioner::apply(const SystemOperator& op, const NodeConstraints& constraints,
                                   const std::vector<Eigen::Matrix3d>& block_inverse,
                                   const Eigen::VectorXd& r, Eigen::VectorXd& z) {
  smooth(constraints, block_inverse, r, z);
  z *= weight_;
  op.multiply(z, product_);
  residual_ = r - product_;
  constraints.filter(residual_);
  restrictToCorners(residual_, coarse_rhs_);
  for (int i = 0; i < coarse_nodes_; ++i) {
    if (constraints.isConstrained(i))
      coarse_rhs_.segment<3>(3 * i) = constraints.filterNode(i, coarse_rhs_.segment<3>(3 * i));
  }
  factor_->solve(coarse_rhs_, coarse_solution_);
  // The correction P e: filtered on the fine nodes (mid-edge nodes of a held face included).
  product_.setZero(r.size());
  prolongAdd(coarse_solution_, product_);
  constraints.filter(product_);
  z += product_;
  op.multiply(z, product_);
  residual_ = r - product_;
  constraints.filter(residual_);
  smooth(constraints, block_inverse, residual_, product_);
  z += weight_ * product_;
}

}  // namespace torsion
