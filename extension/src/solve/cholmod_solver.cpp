#include "torsion/solve/cholmod_solver.h"

#if TORSION_WITH_CHOLMOD
#include <Eigen/CholmodSupport>
#else
#include <Eigen/SparseCholesky>
#endif
#include <cmath>

#include "torsion/fem/quadratic_element.h"
#include "torsion/mesh/tet_mesh.h"

namespace torsion {

struct CholmodSolver::Impl {
  Eigen::SparseMatrix<double> matrix;  // lower triangle, column-major, fixed pattern
  // Node-pair blocks (i >= j) of the pattern, and for each the value index of its 9 entries
  // (row-major within the block; -1 for the upper triangle of a diagonal block).
  std::vector<std::pair<int, int>> blocks;
  std::vector<std::array<int, 9>> block_values;
  // Per element, per (a, b) of its N nodes: block id at [N^2 e + N a + b], -1 if i < j.
  std::vector<int> element_block;
  std::vector<int> diagonal_block;  // per node
  // Nodal pressure (nodal_pressure.h): node n's patch (the nodes of its tets, sorted) in
  // patch_nodes[patch_offsets[n] ..], and the block of every patch pair (i >= j), row by row of
  // the lower triangle, from patch_pair_offsets[n].
  bool nodal_pressure = false;
  std::vector<int> patch_offsets, patch_nodes, patch_pair_offsets, patch_pair_blocks;
  bool analysed = false;
#if TORSION_WITH_CHOLMOD
  Eigen::CholmodDecomposition<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
#else
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>, Eigen::Lower> factor;
#endif
  Eigen::VectorXd rhs, prescribed, q, solution;
};

CholmodSolver::CholmodSolver() : impl_(std::make_unique<Impl>()) {}
CholmodSolver::~CholmodSolver() = default;

const char* CholmodSolver::backend() {
#if TORSION_WITH_CHOLMOD
  return "CHOLMOD";
#else
  return "Eigen SimplicialLLT";
#endif
}

void CholmodSolver::buildPattern(const SystemOperator& op) {
  const FemModel& model = op.model();
  const int n = model.nodeCount();
  const size_t n_per = static_cast<size_t>(model.nodesPerElement());
  const std::vector<int>& element_nodes = model.elementNodes();
  const size_t elements = static_cast<size_t>(model.elementCount());
  // Node-pair blocks (i >= j) present in some element. Lower triangle of the scalar matrix: in a
  // diagonal block keep entries r >= c only; off-diagonal blocks (i > j) are dense.
  std::vector<std::pair<int, int>> pairs;
  pairs.reserve(elements * n_per * (n_per - 1) / 2 + static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    pairs.emplace_back(i, i);
  for (size_t e = 0; e < elements; ++e) {
    const int* nodes = element_nodes.data() + n_per * e;
    for (size_t a = 0; a < n_per; ++a) {
      for (size_t b = 0; b < n_per; ++b) {
        if (nodes[a] > nodes[b]) pairs.emplace_back(nodes[a], nodes[b]);
      }
    }
  }
  // The volumetric stiffness of nodal pressure couples every pair of nodes of a node's patch.
  Impl& m = *impl_;
  m.nodal_pressure = model.nodalPressure();
  m.patch_offsets.assign(1, 0);
  m.patch_nodes.clear();
  if (m.nodal_pressure) {
    const CompressedRows& node_tets = model.mesh().nodeTets();
    std::vector<int> patch;
    for (int node = 0; node < n; ++node) {
      patch.clear();
      for (int k = node_tets.rowBegin(node); k < node_tets.rowEnd(node); ++k) {
        const int* nodes = element_nodes.data() + 4 * node_tets.items[static_cast<size_t>(k)];
        patch.insert(patch.end(), nodes, nodes + 4);
      }
      std::sort(patch.begin(), patch.end());
      patch.erase(std::unique(patch.begin(), patch.end()), patch.end());
      for (size_t a = 0; a < patch.size(); ++a) {
        for (size_t b = 0; b < a; ++b)
          pairs.emplace_back(patch[a], patch[b]);
      }
      m.patch_nodes.insert(m.patch_nodes.end(), patch.begin(), patch.end());
      m.patch_offsets.push_back(static_cast<int>(m.patch_nodes.size()));
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
  m.diagonal_block.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    m.diagonal_block[static_cast<size_t>(i)] = block_of(i, i);
  m.patch_pair_offsets.assign(1, 0);
  m.patch_pair_blocks.clear();
  if (m.nodal_pressure) {
    for (int node = 0; node < n; ++node) {
      const int* patch = m.patch_nodes.data() + m.patch_offsets[static_cast<size_t>(node)];
      const int size = m.patch_offsets[static_cast<size_t>(node) + 1] -
                       m.patch_offsets[static_cast<size_t>(node)];
      for (int a = 0; a < size; ++a) {
        for (int b = 0; b <= a; ++b)
          m.patch_pair_blocks.push_back(block_of(patch[a], patch[b]));
      }
      m.patch_pair_offsets.push_back(static_cast<int>(m.patch_pair_blocks.size()));
    }
  }
  m.element_block.assign(elements * n_per * n_per, -1);
  for (size_t e = 0; e < elements; ++e) {
    const int* nodes = element_nodes.data() + n_per * e;
    for (size_t a = 0; a < n_per; ++a) {
      for (size_t b = 0; b < n_per; ++b) {
        if (nodes[a] >= nodes[b])
          m.element_block[n_per * n_per * e + n_per * a + b] = block_of(nodes[a], nodes[b]);
      }
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
  const double mu = model.material().mu();
  // With nodal pressure the element blocks are deviatoric (lambda -> -2 mu / 3) and the
  // volumetric part is added per node patch below (nodal_pressure.h).
  const double lambda = model.nodalPressure() ? -2.0 * mu / 3.0 : model.material().lambda();
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

  if (model.elementKind() == ElementKind::kTet4) {
    // K_ab = V R (mu (g_a . g_b) I + mu g_b g_a^T + lambda g_a g_b^T) R^T.
    for (int t = 0; t < model.elementCount(); ++t) {
      const TetRestData& rest = model.tetRestData()[static_cast<size_t>(t)];
      const Eigen::Matrix3d& R = op.rotations()[static_cast<size_t>(t)];
      const Eigen::Matrix3d& B = rest.rest_shape_inverse;
      const std::array<Eigen::Vector3d, 4> g = {-(B.row(0) + B.row(1) + B.row(2)).transpose(),
                                                B.row(0).transpose(), B.row(1).transpose(),
                                                B.row(2).transpose()};
      for (size_t a = 0; a < 4; ++a) {
        for (size_t b = 0; b < 4; ++b) {
          const int block = m.element_block[16 * static_cast<size_t>(t) + 4 * a + b];
          if (block < 0) continue;
          const Eigen::Matrix3d local =
              rest.volume * (mu * g[a].dot(g[b]) * Eigen::Matrix3d::Identity() +
                             mu * g[b] * g[a].transpose() + lambda * g[a] * g[b].transpose());
          add_block(block, c * (R * local * R.transpose()));
        }
      }
    }
  } else {
    // The quadrature sum of quadratic_element.h per block.
    for (int e = 0; e < model.elementCount(); ++e) {
      const QuadraticRestData& rest = model.quadraticRestData()[static_cast<size_t>(e)];
      const Eigen::Matrix3d& R = op.rotations()[static_cast<size_t>(e)];
      for (int a = 0; a < 10; ++a) {
        for (int b = 0; b < 10; ++b) {
          const int block = m.element_block[100 * static_cast<size_t>(e) +
                                            10 * static_cast<size_t>(a) + static_cast<size_t>(b)];
          if (block < 0) continue;
          add_block(block, c * quadraticStiffnessBlock(R, rest, mu, lambda, a, b));
        }
      }
    }
  }
  if (m.nodal_pressure) {
    // kappa V_n b_n b_n^T per node n, (b_n)_a = sum_{e ∋ n, a} (V_e / 4) R_e g_a / V_n.
    const CompressedRows& node_tets = model.mesh().nodeTets();
    const std::vector<int>& element_nodes = model.elementNodes();
    const double kappa = model.material().bulkModulus();
    std::vector<Eigen::Vector3d> b;
    for (int node = 0; node < model.nodeCount(); ++node) {
      const int* patch = m.patch_nodes.data() + m.patch_offsets[static_cast<size_t>(node)];
      const int size = m.patch_offsets[static_cast<size_t>(node) + 1] -
                       m.patch_offsets[static_cast<size_t>(node)];
      b.assign(static_cast<size_t>(size), Eigen::Vector3d::Zero());
      for (int k = node_tets.rowBegin(node); k < node_tets.rowEnd(node); ++k) {
        const size_t t = static_cast<size_t>(node_tets.items[static_cast<size_t>(k)]);
        const TetRestData& rest = model.tetRestData()[t];
        const Eigen::Matrix3d& R = op.rotations()[t];
        const Eigen::Matrix3d& B = rest.rest_shape_inverse;
        const std::array<Eigen::Vector3d, 4> g = {-(B.row(0) + B.row(1) + B.row(2)).transpose(),
                                                  B.row(0).transpose(), B.row(1).transpose(),
                                                  B.row(2).transpose()};
        for (size_t a = 0; a < 4; ++a) {
          const size_t at = static_cast<size_t>(
              std::lower_bound(patch, patch + size, element_nodes[4 * t + a]) - patch);
          b[at] += (0.25 * rest.volume) * (R * g[a]);
        }
      }
      const double scale = c * kappa / model.nodeVolumes()[static_cast<size_t>(node)];
      const int* blocks =
          m.patch_pair_blocks.data() + m.patch_pair_offsets[static_cast<size_t>(node)];
      for (size_t a = 0, pair = 0; a < static_cast<size_t>(size); ++a) {
        for (size_t bi = 0; bi <= a; ++bi, ++pair)
          add_block(blocks[pair], scale * b[a] * b[bi].transpose());
      }
    }
  }
  const std::vector<double>& mass = model.nodeMasses();
  for (int i = 0; i < model.nodeCount(); ++i) {
    add_block(m.diagonal_block[static_cast<size_t>(i)],
              op.massCoefficient() * mass[static_cast<size_t>(i)] * Eigen::Matrix3d::Identity());
  }

  // Constraints: A' = S A S + (I - S), block by block. S_i = I (free), 0 (full), I - n n^T.
  if (constraints.constrainedCount() > 0) {
    auto filter_matrix = [&](int node) {
      Eigen::Matrix3d S;
      for (int col = 0; col < 3; ++col)
        S.col(col) = constraints.filterNode(node, Eigen::Vector3d::Unit(col));
      return S;
    };
    for (size_t k = 0; k < m.blocks.size(); ++k) {
      const auto [i, j] = m.blocks[k];
      if (!constraints.isConstrained(i) && !constraints.isConstrained(j)) continue;
      const std::array<int, 9>& idx = m.block_values[k];
      Eigen::Matrix3d block;
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col) {
          // The upper triangle of a diagonal block is not stored: mirror it.
          const int at = idx[static_cast<size_t>(3 * r + col)] >= 0
                             ? idx[static_cast<size_t>(3 * r + col)]
                             : idx[static_cast<size_t>(3 * col + r)];
          block(r, col) = values[at];
        }
      }
      Eigen::Matrix3d filtered = filter_matrix(i) * block * filter_matrix(j);
      if (i == j) filtered += Eigen::Matrix3d::Identity() - filter_matrix(i);
      for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 3; ++col) {
          const int at = idx[static_cast<size_t>(3 * r + col)];
          if (at >= 0) values[at] = filtered(r, col);
        }
      }
    }
  }
  return m.matrix;
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

  const Eigen::SparseMatrix<double>& A = assemble(op, constraints);
  if (!Eigen::Map<const Eigen::VectorXd>(A.valuePtr(), A.nonZeros()).allFinite())
    return brokenDown(report, "the matrix is not finite (overflow)");
  if (!m.analysed) {
    m.factor.analyzePattern(A);
    m.analysed = true;
  }
  m.factor.factorize(A);
  if (m.factor.info() != Eigen::Success)
    return brokenDown(report, "the Cholesky factorisation failed (matrix not positive definite)");
  m.solution = m.factor.solve(m.rhs);
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
