#include "torsion/solve/cholmod_solver.h"

#if TORSION_WITH_CHOLMOD
#include <Eigen/CholmodSupport>
#else
#include <Eigen/SparseCholesky>
#endif
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "constrained_blocks.h"
#include "serial_openmp.h"

namespace torsion {

struct CholmodSolver::Impl {
  Eigen::SparseMatrix<double> matrix;  // lower triangle, column-major, fixed pattern
  // Node-pair blocks (i >= j) of the pattern, and for each the value index of its 9 entries
  // (row-major within the block; -1 for the upper triangle of a diagonal block).
  std::vector<std::pair<int, int>> blocks;
  std::vector<std::array<int, 9>> block_values;
  // Per slot of the operator's upper-triangle K (row n, column c >= n): the block (c, n) here.
  std::vector<int> slot_block;
  // Nodal pressure (nodal_pressure.h): the block of every pair (a >= b) of node n's patch, row by
  // row of the lower triangle, from patch_pair_offsets[n].
  bool nodal_pressure = false;
  std::vector<int> patch_pair_offsets, patch_pair_blocks;
  // Scratch for one node's patch (SystemOperator::volumetricPatch).
  std::vector<int> patch_nodes;
  std::vector<Eigen::Vector3d> patch_weights;
  bool analysed = false;
  bool matrix_finite = false, factor_valid = false;  // of the last factorize()
#if TORSION_WITH_CHOLMOD
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
#else
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
#endif
  Eigen::VectorXd rhs, prescribed, q, solution;
};

#if TORSION_WITH_CHOLMOD
namespace {
// Eigen's wrapper keeps CHOLMOD's factor protected; its size is what a solve streams.
class CholmodWithFactorSize
    : public Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> {
 public:
  const cholmod_factor* factorPtr() const { return this->m_cholmodFactor; }
};
}  // namespace
#endif

struct SparseCholesky::Impl {
#if TORSION_WITH_CHOLMOD
  CholmodWithFactorSize factor;
#else
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
#endif
  Eigen::Index rows = -1, entries = -1;  // the analysed pattern
};

#if TORSION_WITH_CHOLMOD
namespace {
// A matrix that is not positive definite is an outcome the callers report (a hyperelastic Newton
// direction falls back to the projected stiffness, a lagged preconditioner refactorises), not a
// message for the user's terminal: CHOLMOD's own printing is off.
void silence(cholmod_common& common) {
  common.print = 0;
}
}  // namespace
#endif

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {
#if TORSION_WITH_CHOLMOD
  silence(impl_->factor.cholmod());
#endif
}
SparseCholesky::~SparseCholesky() = default;

bool SparseCholesky::factorize(const Eigen::SparseMatrix<double>& lower) {
  Impl& m = *impl_;
  valid_ = false;
  if (!Eigen::Map<const Eigen::VectorXd>(lower.valuePtr(), lower.nonZeros()).allFinite())
    return false;
  const detail::SerialOpenMpScope serial;
  if (m.rows != lower.rows() || m.entries != lower.nonZeros()) {
    m.factor.analyzePattern(lower);
    m.rows = lower.rows();
    m.entries = lower.nonZeros();
  }
  m.factor.factorize(lower);
  valid_ = m.factor.info() == Eigen::Success;
  return valid_;
}

void SparseCholesky::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const detail::SerialOpenMpScope serial;
  x = impl_->factor.solve(b);
}

void SparseCholesky::solve(const Eigen::MatrixXd& B, Eigen::MatrixXd& X) const {
  const detail::SerialOpenMpScope serial;
  X = impl_->factor.solve(B);
}

long SparseCholesky::factorEntries() const {
  if (!valid_) return 0;
#if TORSION_WITH_CHOLMOD
  // Eigen's wrapper does not expose the factor: read CHOLMOD's own count.
  const cholmod_factor* L = impl_->factor.factorPtr();
  return L ? static_cast<long>(L->is_super ? L->xsize : L->nzmax) : 0;
#else
  return static_cast<long>(impl_->factor.matrixL().nestedExpression().nonZeros());
#endif
}

CholmodSolver::CholmodSolver() : impl_(std::make_unique<Impl>()) {
#if TORSION_WITH_CHOLMOD
  silence(impl_->factor.cholmod());
#endif
}
CholmodSolver::~CholmodSolver() = default;

const char* CholmodSolver::backend() {
#if TORSION_WITH_CHOLMOD
  return "CHOLMOD";
#else
  return "Eigen SimplicialLLT";
#endif
}

void CholmodSolver::buildPattern(const SystemOperator& op) {
  const int n = op.model().nodeCount();
  const std::vector<int>& row_offsets = op.blockRowOffsets();
  const std::vector<int>& columns = op.blockColumns();
  Impl& m = *impl_;
  // The lower block triangle is the operator's upper one transposed: its slot (row, column)
  // is the block (column, row) here. Lower triangle of the scalar matrix: in a diagonal block
  // keep entries r >= c only; off-diagonal blocks (i > j) are dense.
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(columns.size());
  for (int row = 0; row < n; ++row) {
    for (int s = row_offsets[static_cast<size_t>(row)];
         s < row_offsets[static_cast<size_t>(row) + 1]; ++s)
      pairs.emplace_back(columns[static_cast<size_t>(s)], row);
  }
  // The volumetric stiffness of nodal pressure couples every pair of nodes of a node's patch
  // (nodes two tets apart: outside the operator's pattern).
  m.nodal_pressure = op.model().nodalPressure();
  if (m.nodal_pressure) {
    for (int node = 0; node < n; ++node) {
      op.volumetricPatch(node, m.patch_nodes, m.patch_weights);
      for (size_t a = 0; a < m.patch_nodes.size(); ++a) {
        for (size_t b = 0; b < a; ++b)
          pairs.emplace_back(m.patch_nodes[a], m.patch_nodes[b]);
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());

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
  m.matrix.resize(3 * n, 3 * n);
  m.matrix.setFromTriplets(triplets.begin(), triplets.end());
  m.matrix.makeCompressed();

  // Value index of every stored entry, found once.
  auto value_index = [&](int row, int col) -> int {
    const int* outer = m.matrix.outerIndexPtr();
    const int* inner = m.matrix.innerIndexPtr();
    const int* first = inner + outer[col];
    const int* last = inner + outer[col + 1];
    const int* it = std::lower_bound(first, last, row);
    return (it != last && *it == row) ? static_cast<int>(it - inner) : -1;
  };
  m.blocks = pairs;
  m.block_values.resize(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k) {
    const auto [i, j] = pairs[k];
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        m.block_values[k][static_cast<size_t>(3 * r + c)] = value_index(3 * i + r, 3 * j + c);
    }
  }
  auto block_of = [&](int i, int j) {
    return static_cast<int>(std::lower_bound(pairs.begin(), pairs.end(), std::make_pair(i, j)) -
                            pairs.begin());
  };
  m.slot_block.resize(columns.size());
  for (int row = 0; row < n; ++row) {
    for (int s = row_offsets[static_cast<size_t>(row)];
         s < row_offsets[static_cast<size_t>(row) + 1]; ++s)
      m.slot_block[static_cast<size_t>(s)] = block_of(columns[static_cast<size_t>(s)], row);
  }
  m.patch_pair_offsets.assign(1, 0);
  m.patch_pair_blocks.clear();
  if (m.nodal_pressure) {
    for (int node = 0; node < n; ++node) {
      op.volumetricPatch(node, m.patch_nodes, m.patch_weights);
      const std::vector<int>& patch = m.patch_nodes;
      for (size_t a = 0; a < patch.size(); ++a) {
        for (size_t b = 0; b <= a; ++b)
          m.patch_pair_blocks.push_back(block_of(patch[a], patch[b]));
      }
      m.patch_pair_offsets.push_back(static_cast<int>(m.patch_pair_blocks.size()));
    }
  }
}

const Eigen::SparseMatrix<double>& CholmodSolver::assemble(const SystemOperator& op,
                                                           const NodeConstraints& constraints) {
  Impl& m = *impl_;
  if (m.matrix.rows() != 3 * op.model().nodeCount() ||
      m.nodal_pressure != op.model().nodalPressure()) {
    buildPattern(op);
    m.analysed = false;
  }
  const FemModel& model = op.model();
  const double c = op.stiffnessCoefficient();
  double* values = m.matrix.valuePtr();
  std::fill(values, values + m.matrix.nonZeros(), 0.0);

  auto add_block = [&](int block, const Eigen::Matrix3d& value) {
    const std::array<int, 9>& idx = m.block_values[static_cast<size_t>(block)];
    for (int r = 0; r < 3; ++r) {
      for (int col = 0; col < 3; ++col) {
        const int k = idx[static_cast<size_t>(3 * r + col)];
        if (k >= 0) values[k] += value(r, col);
      }
    }
  };

  // c K from the operator's blocks: slot (row n, column j) is K(n, j) = K(j, n)^T.
  const std::vector<Eigen::Matrix3d>& stiffness = op.stiffnessBlocks();
  for (size_t s = 0; s < stiffness.size(); ++s)
    add_block(m.slot_block[s], c * stiffness[s].transpose());
  if (m.nodal_pressure) {
    // kappa / V_n w_n w_n^T per node n (SystemOperator::volumetricPatch).
    const double kappa = model.material().bulkModulus();
    for (int node = 0; node < model.nodeCount(); ++node) {
      op.volumetricPatch(node, m.patch_nodes, m.patch_weights);
      const std::vector<Eigen::Vector3d>& w = m.patch_weights;
      const double scale = c * kappa / model.nodeVolumes()[static_cast<size_t>(node)];
      const int* blocks =
          m.patch_pair_blocks.data() + m.patch_pair_offsets[static_cast<size_t>(node)];
      for (size_t a = 0, pair = 0; a < w.size(); ++a) {
        for (size_t b = 0; b <= a; ++b, ++pair)
          add_block(blocks[pair], scale * w[a] * w[b].transpose());
      }
    }
  }
  const std::vector<double>& mass = model.nodeMasses();
  const std::vector<int>& row_offsets = op.blockRowOffsets();
  for (int i = 0; i < model.nodeCount(); ++i) {  // the diagonal block leads its row
    add_block(m.slot_block[static_cast<size_t>(row_offsets[static_cast<size_t>(i)])],
              op.massCoefficient() * mass[static_cast<size_t>(i)] * Eigen::Matrix3d::Identity());
  }

  // Constraints: A' = S A S + (I - S), block by block.
  detail::applyConstraintsToBlocks(constraints, m.blocks, m.block_values, values);
  return m.matrix;
}

bool CholmodSolver::factorize(const SystemOperator& op, const NodeConstraints& constraints) {
  Impl& m = *impl_;
  m.factor_valid = false;
  const Eigen::SparseMatrix<double>& A = assemble(op, constraints);
  m.matrix_finite = Eigen::Map<const Eigen::VectorXd>(A.valuePtr(), A.nonZeros()).allFinite();
  if (!m.matrix_finite) return false;
  const detail::SerialOpenMpScope serial;
  if (!m.analysed) {
    m.factor.analyzePattern(A);
    m.analysed = true;
  }
  m.factor.factorize(A);
  m.factor_valid = m.factor.info() == Eigen::Success;
  return m.factor_valid;
}

bool CholmodSolver::factorized() const {
  return impl_->factor_valid;
}

void CholmodSolver::applyInverse(const NodeConstraints& constraints, const Eigen::VectorXd& r,
                                 Eigen::VectorXd& z) const {
  Eigen::VectorXd filtered = r;
  constraints.filter(filtered);
  {
    const detail::SerialOpenMpScope serial;
    z = impl_->factor.solve(filtered);
  }
  constraints.filter(z);
}

LinearSolveReport CholmodSolver::solve(const SystemOperator& op, const NodeConstraints& constraints,
                                       const Eigen::VectorXd& b, Eigen::VectorXd& v) {
  Impl& m = *impl_;
  LinearSolveReport report;
  // Right-hand side of the reduced system: S (b - A v_c).
  m.prescribed.setZero(b.size());
  constraints.impose(m.prescribed);
  op.multiply(m.prescribed, m.q);
  m.rhs = b - m.q;
  constraints.filter(m.rhs);
  const double reference = m.rhs.norm();
  report.relative_residual = std::numeric_limits<double>::infinity();
  if (!std::isfinite(reference))  // an overflowed system must not pass as solved
    return brokenDown(report, "the right-hand side or the matrix is not finite (overflow)");

  if (!factorize(op, constraints)) {
    return brokenDown(report, m.matrix_finite ? "the Cholesky factorisation failed (matrix not "
                                                "positive definite)"
                                              : "the matrix is not finite (overflow)");
  }
  {
    const detail::SerialOpenMpScope serial;
    m.solution = m.factor.solve(m.rhs);
  }
  constraints.filter(m.solution);
  v = m.prescribed + m.solution;

  // Honest residual of the result, measured with the matrix-free operator.
  op.multiply(v, m.q);
  m.rhs = b - m.q;
  constraints.filter(m.rhs);
  report.relative_residual = reference > 0 ? m.rhs.norm() / reference : 0.0;
  if (!std::isfinite(report.relative_residual) || !v.allFinite())
    return brokenDown(report, "the residual or the solution became non-finite");
  report.converged = report.relative_residual < 1e-6;
  return report;
}

}  // namespace torsion
