#include "torsion/solve/system_operator.h"

#include <algorithm>
#include <cassert>

namespace torsion {

namespace {
constexpr int kTetGrain = 512;
constexpr int kNodeGrain = 256;

// Shape-function gradients of a tet's four nodes from its inverse rest shape.
std::array<Eigen::Vector3d, 4> shapeGradients(const Eigen::Matrix3d& B) {
  return {Eigen::Vector3d(-(B.row(0) + B.row(1) + B.row(2)).transpose()), B.row(0).transpose(),
          B.row(1).transpose(), B.row(2).transpose()};
}
}  // namespace

SystemOperator::SystemOperator(std::shared_ptr<const FemModel> model, const Parallel& parallel)
    : model_(std::move(model)), parallel_(parallel) {
  const TetMesh& mesh = model_->mesh();
  rotations_.assign(static_cast<size_t>(mesh.tetCount()), Eigen::Matrix3d::Identity());
  rotated_gradients_.resize(static_cast<size_t>(mesh.tetCount()));
  const CompressedRows& node_tets = mesh.nodeTets();
  node_offsets_ = node_tets.offsets;
  node_entries_.resize(node_tets.items.size());
  for (int n = 0; n < mesh.nodeCount(); ++n) {
    for (int k = node_tets.rowBegin(n); k < node_tets.rowEnd(n); ++k) {
      const int t = node_tets.items[static_cast<size_t>(k)];
      const Tet& tet = mesh.tets()[static_cast<size_t>(t)];
      int local = 0;
      while (tet[static_cast<size_t>(local)] != n)
        ++local;
      node_entries_[static_cast<size_t>(k)] = 4 * t + local;
    }
  }
  buildPattern();
}

void SystemOperator::buildPattern() {
  // K is symmetric, so a block row stores only its diagonal block and the blocks right of it
  // (columns > row); the blocks left of the diagonal are read, transposed, from the rows that
  // store them. Assembly computes 10 blocks per tet instead of 16.
  const TetMesh& mesh = model_->mesh();
  const int n = mesh.nodeCount();
  row_offsets_.assign(static_cast<size_t>(n) + 1, 0);
  block_columns_.clear();
  entry_slots_.assign(4 * node_entries_.size(), -1);
  diagonal_slots_.assign(static_cast<size_t>(n), -1);
  std::vector<int> columns;
  for (int row = 0; row < n; ++row) {
    const int begin = node_offsets_[static_cast<size_t>(row)];
    const int end = node_offsets_[static_cast<size_t>(row) + 1];
    columns.assign(1, row);  // a node without tets still gets its (mass) diagonal block
    for (int k = begin; k < end; ++k) {
      const Tet& tet = mesh.tets()[static_cast<size_t>(node_entries_[static_cast<size_t>(k)] / 4)];
      for (int node : tet)
        if (node > row) columns.push_back(node);
    }
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    const int row_begin = static_cast<int>(block_columns_.size());
    block_columns_.insert(block_columns_.end(), columns.begin(), columns.end());
    row_offsets_[static_cast<size_t>(row) + 1] = static_cast<int>(block_columns_.size());
    diagonal_slots_[static_cast<size_t>(row)] = row_begin;  // columns[0] == row
    for (int k = begin; k < end; ++k) {
      const Tet& tet = mesh.tets()[static_cast<size_t>(node_entries_[static_cast<size_t>(k)] / 4)];
      for (size_t b = 0; b < 4; ++b) {
        if (tet[b] < row) continue;
        entry_slots_[4 * static_cast<size_t>(k) + b] =
            row_begin + static_cast<int>(std::lower_bound(columns.begin(), columns.end(), tet[b]) -
                                         columns.begin());
      }
    }
  }
  // Blocks left of the diagonal of row c: the stored blocks (row r < c, column c), by row.
  lower_offsets_.assign(static_cast<size_t>(n) + 1, 0);
  for (int row = 0; row < n; ++row) {
    for (int s = row_offsets_[static_cast<size_t>(row)] + 1;
         s < row_offsets_[static_cast<size_t>(row) + 1]; ++s)
      ++lower_offsets_[static_cast<size_t>(block_columns_[static_cast<size_t>(s)]) + 1];
  }
  for (int row = 0; row < n; ++row)
    lower_offsets_[static_cast<size_t>(row) + 1] += lower_offsets_[static_cast<size_t>(row)];
  lower_slots_.assign(static_cast<size_t>(lower_offsets_.back()), -1);
  lower_columns_.assign(lower_slots_.size(), -1);
  std::vector<int> fill(lower_offsets_.begin(), lower_offsets_.end() - 1);
  for (int row = 0; row < n; ++row) {  // ascending rows: each list comes out sorted
    for (int s = row_offsets_[static_cast<size_t>(row)] + 1;
         s < row_offsets_[static_cast<size_t>(row) + 1]; ++s) {
      const size_t at =
          static_cast<size_t>(fill[static_cast<size_t>(block_columns_[static_cast<size_t>(s)])]++);
      lower_slots_[at] = s;
      lower_columns_[at] = row;
    }
  }
  block_values_.assign(block_columns_.size(), Eigen::Matrix3d::Zero());
  assembled_ = false;
}

void SystemOperator::assemble() const {
  if (assembled_) return;
  const TetMesh& mesh = model_->mesh();
  const double mu = model_->material().mu();
  const double lambda = model_->material().lambda();
  // Pass 1, per tet: the rotated shape gradients R g_a.
  parallel_.forRange(mesh.tetCount(), kTetGrain, [&](int begin, int end) {
    for (int t = begin; t < end; ++t) {
      const size_t ti = static_cast<size_t>(t);
      const std::array<Eigen::Vector3d, 4> g =
          shapeGradients(model_->tetRestData()[ti].rest_shape_inverse);
      for (size_t a = 0; a < 4; ++a)
        rotated_gradients_[ti][a] = rotations_[ti] * g[a];
    }
  });
  // Pass 2, per block row: K_ab = V (mu (g_a . g_b) I + mu (R g_b)(R g_a)^T + lambda (R g_a)(R
  // g_b)^T) for every tet of the row's node a (rotating the rest-frame block R Ke_ab R^T).
  parallel_.forRange(mesh.nodeCount(), kNodeGrain, [&](int begin, int end) {
    for (int row = begin; row < end; ++row) {
      const size_t r = static_cast<size_t>(row);
      for (int s = row_offsets_[r]; s < row_offsets_[r + 1]; ++s)
        block_values_[static_cast<size_t>(s)].setZero();
      for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
        const int entry = node_entries_[static_cast<size_t>(k)];
        const size_t t = static_cast<size_t>(entry / 4), a = static_cast<size_t>(entry % 4);
        const TetRestData& rest = model_->tetRestData()[t];
        const std::array<Eigen::Vector3d, 4>& rg = rotated_gradients_[t];
        const double mu_v = mu * rest.volume, lambda_v = lambda * rest.volume;
        const Eigen::Vector3d& u = rg[a];
        const Eigen::Vector3d q = lambda_v * u;
        for (size_t b = 0; b < 4; ++b) {
          const int slot = entry_slots_[4 * static_cast<size_t>(k) + b];
          if (slot < 0) continue;  // left of the diagonal: stored by the other node's row
          const Eigen::Vector3d& w = rg[b];
          const Eigen::Vector3d p = mu_v * w;
          // g_a . g_b is rotation-invariant: take it from the rotated gradients.
          const double diagonal = mu_v * u.dot(w);
          double* block = block_values_[static_cast<size_t>(slot)].data();  // column-major
          for (int c = 0; c < 3; ++c) {
            for (int i = 0; i < 3; ++i)
              block[3 * c + i] += p[i] * u[c] + q[i] * w[c];
            block[4 * c] += diagonal;
          }
        }
      }
    }
  });
  assembled_ = true;
}

void SystemOperator::setCoefficients(double mass_coefficient, double stiffness_coefficient) {
  mass_coefficient_ = mass_coefficient;
  stiffness_coefficient_ = stiffness_coefficient;
}

void SystemOperator::apply(const Eigen::VectorXd& y, Eigen::VectorXd& out, double mass_scale,
                           double stiffness_scale) const {
  assemble();
  const std::vector<double>& mass = model_->nodeMasses();
  out.resize(y.size());
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    for (int row = begin; row < end; ++row) {
      const size_t r = static_cast<size_t>(row);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int s = row_offsets_[r]; s < row_offsets_[r + 1]; ++s) {
        sum.noalias() += block_values_[static_cast<size_t>(s)] *
                         y.segment<3>(3 * block_columns_[static_cast<size_t>(s)]);
      }
      for (int l = lower_offsets_[r]; l < lower_offsets_[r + 1]; ++l) {
        sum.noalias() +=
            block_values_[static_cast<size_t>(lower_slots_[static_cast<size_t>(l)])].transpose() *
            y.segment<3>(3 * lower_columns_[static_cast<size_t>(l)]);
      }
      out.segment<3>(3 * row) =
          stiffness_scale * sum + (mass_scale * mass[r]) * y.segment<3>(3 * row);
    }
  });
}

void SystemOperator::gather(const std::vector<std::array<Eigen::Vector3d, 4>>& tet_values,
                            double scale, Eigen::VectorXd& out) const {
  const int node_count = model_->nodeCount();
  out.resize(3 * node_count);
  parallel_.forRange(node_count, kNodeGrain, [&](int begin, int end) {
    for (int n = begin; n < end; ++n) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = node_offsets_[static_cast<size_t>(n)];
           k < node_offsets_[static_cast<size_t>(n) + 1]; ++k) {
        const int entry = node_entries_[static_cast<size_t>(k)];
        sum += tet_values[static_cast<size_t>(entry / 4)][static_cast<size_t>(entry % 4)];
      }
      out.segment<3>(3 * n) = scale * sum;
    }
  });
}

void SystemOperator::multiply(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  apply(y, out, mass_coefficient_, stiffness_coefficient_);
}

void SystemOperator::multiplyStiffness(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  apply(y, out, 0.0, 1.0);
}

void SystemOperator::diagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const {
  assemble();
  const std::vector<double>& mass = model_->nodeMasses();
  blocks.resize(static_cast<size_t>(model_->nodeCount()));
  for (size_t n = 0; n < blocks.size(); ++n) {
    blocks[n] = mass_coefficient_ * mass[n] * Eigen::Matrix3d::Identity() +
                stiffness_coefficient_ * block_values_[static_cast<size_t>(diagonal_slots_[n])];
  }
}

void SystemOperator::replaceModel(std::shared_ptr<const FemModel> model) {
  assert(&model->mesh() == &model_->mesh() && "replaceModel wants a model of the same mesh");
  model_ = std::move(model);
  assembled_ = false;  // K holds the old material's mu and lambda
}

}  // namespace torsion
