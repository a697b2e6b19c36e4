#include "torsion/solve/system_operator.h"

#include <algorithm>
#include <cassert>

#include "torsion/fem/nodal_pressure.h"

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
  const int elements = model_->elementCount();
  const int n_per = model_->nodesPerElement();
  const std::vector<int>& element_nodes = model_->elementNodes();
  nodes_per_element_ = n_per;
  rotations_.assign(static_cast<size_t>(elements), Eigen::Matrix3d::Identity());
  const int quadrature = model_->elementKind() == ElementKind::kTet10 ? kTet10QuadraturePoints : 1;
  rotated_gradients_.resize(static_cast<size_t>(elements) *
                            static_cast<size_t>(quadrature * n_per));
  // Node -> (element, local index), elements ascending per node.
  const int node_count = model_->nodeCount();
  node_offsets_.assign(static_cast<size_t>(node_count) + 1, 0);
  for (int node : element_nodes)
    ++node_offsets_[static_cast<size_t>(node) + 1];
  for (int i = 0; i < node_count; ++i)
    node_offsets_[static_cast<size_t>(i) + 1] += node_offsets_[static_cast<size_t>(i)];
  node_entries_.assign(element_nodes.size(), -1);
  std::vector<int> fill(node_offsets_.begin(), node_offsets_.end() - 1);
  for (size_t entry = 0; entry < element_nodes.size(); ++entry)  // ascending elements
    node_entries_[static_cast<size_t>(fill[static_cast<size_t>(element_nodes[entry])]++)] =
        static_cast<int>(entry);
  buildPattern();
  if (model_->elementKind() == ElementKind::kTet4) buildPatches();
}

void SystemOperator::buildPattern() {
  // K is symmetric, so a block row stores only its diagonal block and the blocks right of it
  // (columns > row); the blocks left of the diagonal are read, transposed, from the rows that
  // store them. Assembly computes 10 blocks per tet4 instead of 16 (55 of 100 per tet10).
  const int n = model_->nodeCount();
  const size_t n_per = static_cast<size_t>(nodes_per_element_);
  const std::vector<int>& element_nodes = model_->elementNodes();
  // The nodes of the element of node entry k.
  auto element_of = [&](int k) {
    return element_nodes.data() +
           n_per * static_cast<size_t>(node_entries_[static_cast<size_t>(k)] / nodes_per_element_);
  };
  row_offsets_.assign(static_cast<size_t>(n) + 1, 0);
  block_columns_.clear();
  entry_slots_.assign(n_per * node_entries_.size(), -1);
  diagonal_slots_.assign(static_cast<size_t>(n), -1);
  std::vector<int> columns;
  for (int row = 0; row < n; ++row) {
    const int begin = node_offsets_[static_cast<size_t>(row)];
    const int end = node_offsets_[static_cast<size_t>(row) + 1];
    columns.assign(1, row);  // a node without elements still gets its (mass) diagonal block
    for (int k = begin; k < end; ++k) {
      const int* nodes = element_of(k);
      for (size_t b = 0; b < n_per; ++b)
        if (nodes[b] > row) columns.push_back(nodes[b]);
    }
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    const int row_begin = static_cast<int>(block_columns_.size());
    block_columns_.insert(block_columns_.end(), columns.begin(), columns.end());
    row_offsets_[static_cast<size_t>(row) + 1] = static_cast<int>(block_columns_.size());
    diagonal_slots_[static_cast<size_t>(row)] = row_begin;  // columns[0] == row
    for (int k = begin; k < end; ++k) {
      const int* nodes = element_of(k);
      for (size_t b = 0; b < n_per; ++b) {
        if (nodes[b] < row) continue;
        entry_slots_[n_per * static_cast<size_t>(k) + b] =
            row_begin +
            static_cast<int>(std::lower_bound(columns.begin(), columns.end(), nodes[b]) -
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
  if (model_->elementKind() == ElementKind::kTet10) {
    assembleElements<10, kTet10QuadraturePoints>();
  } else {
    assembleElements<4, 1>();
  }
  assembled_ = true;
}

template <int N, int Q>
void SystemOperator::assembleElements() const {
  const double mu = model_->material().mu();
  // With nodal pressure the blocks hold the deviatoric part only (nodal_pressure.h): the same
  // formula with lambda replaced by -2 mu / 3; the volumetric part is applied in factored form.
  const double lambda = model_->nodalPressure() ? -2.0 * mu / 3.0 : model_->material().lambda();
  constexpr size_t kPerElement = static_cast<size_t>(N * Q);
  // Pass 1, per element: the rotated shape gradients R g_a at each quadrature point.
  parallel_.forRange(model_->elementCount(), kTetGrain, [&](int begin, int end) {
    for (int e = begin; e < end; ++e) {
      const size_t ei = static_cast<size_t>(e);
      Eigen::Vector3d* out = rotated_gradients_.data() + kPerElement * ei;
      if constexpr (N == 4) {
        const std::array<Eigen::Vector3d, 4> g =
            shapeGradients(model_->tetRestData()[ei].rest_shape_inverse);
        for (size_t a = 0; a < 4; ++a)
          out[a] = rotations_[ei] * g[a];
      } else {
        const QuadraticRestData& rest = model_->quadraticRestData()[ei];
        for (size_t q = 0; q < static_cast<size_t>(Q); ++q)
          for (size_t a = 0; a < static_cast<size_t>(N); ++a)
            out[static_cast<size_t>(N) * q + a] = rotations_[ei] * rest.gradients[q][a];
      }
    }
  });
  // Pass 2, per block row: K_ab = sum_q w_q (mu (g_a . g_b) I + mu (R g_b)(R g_a)^T +
  // lambda (R g_a)(R g_b)^T) for every element of the row's node a (rotating the rest-frame block
  // R Ke_ab R^T); w is V for tet4 (one point), V / 4 for tet10.
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    for (int row = begin; row < end; ++row) {
      const size_t r = static_cast<size_t>(row);
      for (int s = row_offsets_[r]; s < row_offsets_[r + 1]; ++s)
        block_values_[static_cast<size_t>(s)].setZero();
      for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
        const int entry = node_entries_[static_cast<size_t>(k)];
        const size_t e = static_cast<size_t>(entry / N), a = static_cast<size_t>(entry % N);
        double weight;
        if constexpr (N == 4) {
          weight = model_->tetRestData()[e].volume;
        } else {
          weight = model_->quadraticRestData()[e].volume / Q;
        }
        const Eigen::Vector3d* rg = rotated_gradients_.data() + kPerElement * e;
        const double mu_v = mu * weight, lambda_v = lambda * weight;
        for (size_t b = 0; b < static_cast<size_t>(N); ++b) {
          const int slot = entry_slots_[static_cast<size_t>(N) * static_cast<size_t>(k) + b];
          if (slot < 0) continue;  // left of the diagonal: stored by the other node's row
          double* block = block_values_[static_cast<size_t>(slot)].data();  // column-major
          for (size_t q = 0; q < static_cast<size_t>(Q); ++q) {
            const Eigen::Vector3d& u = rg[static_cast<size_t>(N) * q + a];
            const Eigen::Vector3d& w = rg[static_cast<size_t>(N) * q + b];
            const Eigen::Vector3d p = mu_v * w;
            const Eigen::Vector3d qv = lambda_v * u;
            // g_a . g_b is rotation-invariant: take it from the rotated gradients.
            const double diagonal = mu_v * u.dot(w);
            for (int c = 0; c < 3; ++c) {
              for (int i = 0; i < 3; ++i)
                block[3 * c + i] += p[i] * u[c] + qv[i] * w[c];
              block[4 * c] += diagonal;
            }
          }
        }
      }
    }
  });
}

void SystemOperator::setCoefficients(double mass_coefficient, double stiffness_coefficient) {
  mass_coefficient_ = mass_coefficient;
  stiffness_coefficient_ = stiffness_coefficient;
}

void SystemOperator::nodalPressureIncrements(const Eigen::VectorXd& y) const {
  // dt_e = sum_a (R_e g_a) . y_a, dtheta_n (node average), then V_e kappa mean(dtheta) per tet.
  const std::vector<int>& nodes = model_->elementNodes();
  const int tets = model_->elementCount();
  tet_scalars_.resize(static_cast<size_t>(tets));
  node_scalars_.resize(static_cast<size_t>(model_->nodeCount()));
  parallel_.forRange(tets, kTetGrain, [&](int begin, int end) {
    for (int t = begin; t < end; ++t) {
      const size_t i = 4 * static_cast<size_t>(t);
      double trace = 0;
      for (size_t a = 0; a < 4; ++a)
        trace += rotated_gradients_[i + a].dot(y.segment<3>(3 * nodes[i + a]));
      tet_scalars_[static_cast<size_t>(t)] = trace;
    }
  });
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    averageOverNodeTets(*model_, tet_scalars_, begin, end, node_scalars_);
  });
  parallel_.forRange(tets, kTetGrain, [&](int begin, int end) {
    averageOverTetNodes(*model_, node_scalars_, model_->material().bulkModulus(), begin, end,
                        tet_scalars_);
    for (int t = begin; t < end; ++t)
      tet_scalars_[static_cast<size_t>(t)] *= model_->tetRestData()[static_cast<size_t>(t)].volume;
  });
}

void SystemOperator::apply(const Eigen::VectorXd& y, Eigen::VectorXd& out, double mass_scale,
                           double stiffness_scale) const {
  assemble();
  const std::vector<double>& mass = model_->nodeMasses();
  out.resize(y.size());
  const bool nodal_pressure = model_->nodalPressure();
  if (nodal_pressure) nodalPressureIncrements(y);
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
      if (nodal_pressure) {  // K_vol y at this node: sum over its tets of V_e dpbar_e R_e g_a
        for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
          const int entry = node_entries_[static_cast<size_t>(k)];
          sum.noalias() += tet_scalars_[static_cast<size_t>(entry / 4)] *
                           rotated_gradients_[static_cast<size_t>(entry)];
        }
      }
      out.segment<3>(3 * row) =
          stiffness_scale * sum + (mass_scale * mass[r]) * y.segment<3>(3 * row);
    }
  });
}

void SystemOperator::gather(const std::vector<Eigen::Vector3d>& element_values, double scale,
                            Eigen::VectorXd& out) const {
  const int node_count = model_->nodeCount();
  out.resize(3 * node_count);
  parallel_.forRange(node_count, kNodeGrain, [&](int begin, int end) {
    for (int n = begin; n < end; ++n) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = node_offsets_[static_cast<size_t>(n)];
           k < node_offsets_[static_cast<size_t>(n) + 1]; ++k)
        sum += element_values[static_cast<size_t>(node_entries_[static_cast<size_t>(k)])];
      out.segment<3>(3 * n) = scale * sum;
    }
  });
}

void SystemOperator::multiply(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  apply(y, out, mass_coefficient_, stiffness_coefficient_);
  if (added_term_ != nullptr) added_term_->addProduct(y, out);
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
  if (model_->nodalPressure()) addNodalPressureDiagonal(blocks);
  if (added_term_ != nullptr) added_term_->addDiagonalBlocks(blocks);
}

void SystemOperator::buildPatches() {
  // Row i's patch: the nodes of its tets, sorted; the patch slot of every (node entry, local node).
  const std::vector<int>& nodes = model_->elementNodes();
  const int n = model_->nodeCount();
  patch_offsets_.assign(1, 0);
  patch_nodes_.clear();
  patch_slots_.assign(4 * node_entries_.size(), -1);
  std::vector<int> patch;
  for (int row = 0; row < n; ++row) {
    const size_t r = static_cast<size_t>(row);
    patch.clear();
    for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
      const size_t t = static_cast<size_t>(node_entries_[static_cast<size_t>(k)] / 4);
      patch.insert(patch.end(), nodes.begin() + static_cast<std::ptrdiff_t>(4 * t),
                   nodes.begin() + static_cast<std::ptrdiff_t>(4 * t + 4));
    }
    std::sort(patch.begin(), patch.end());
    patch.erase(std::unique(patch.begin(), patch.end()), patch.end());
    for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
      const size_t t = static_cast<size_t>(node_entries_[static_cast<size_t>(k)] / 4);
      for (size_t b = 0; b < 4; ++b) {
        patch_slots_[4 * static_cast<size_t>(k) + b] = static_cast<int>(
            std::lower_bound(patch.begin(), patch.end(), nodes[4 * t + b]) - patch.begin());
      }
    }
    patch_nodes_.insert(patch_nodes_.end(), patch.begin(), patch.end());
    patch_offsets_.push_back(static_cast<int>(patch_nodes_.size()));
  }
}

void SystemOperator::addNodalPressureDiagonal(std::vector<Eigen::Matrix3d>& blocks) const {
  // Block (i, i) of sum_n kappa V_n b_n b_n^T: for each node n sharing a tet with i,
  // c_n = (b_n)_i = sum_{e ∋ n, i} (V_e / 4) R_e g_i / V_n, and the block gains kappa V_n c_n
  // c_n^T.
  const double scale = stiffness_coefficient_ * model_->material().bulkModulus();
  const std::vector<double>& node_volume = model_->nodeVolumes();
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    std::vector<Eigen::Vector3d> c;  // V_n c_n per patch slot
    for (int row = begin; row < end; ++row) {
      const size_t r = static_cast<size_t>(row);
      const int first = patch_offsets_[r];
      c.assign(static_cast<size_t>(patch_offsets_[r + 1] - first), Eigen::Vector3d::Zero());
      for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
        const int entry = node_entries_[static_cast<size_t>(k)];
        const Eigen::Vector3d g =
            (0.25 * model_->tetRestData()[static_cast<size_t>(entry / 4)].volume) *
            rotated_gradients_[static_cast<size_t>(entry)];
        for (size_t b = 0; b < 4; ++b)
          c[static_cast<size_t>(patch_slots_[4 * static_cast<size_t>(k) + b])] += g;
      }
      for (size_t j = 0; j < c.size(); ++j) {
        const double weight =
            scale / node_volume[static_cast<size_t>(patch_nodes_[static_cast<size_t>(first) + j])];
        blocks[r].noalias() += weight * c[j] * c[j].transpose();
      }
    }
  });
}

const std::vector<Eigen::Matrix3d>& SystemOperator::stiffnessBlocks() const {
  assemble();
  return block_values_;
}

void SystemOperator::volumetricPatch(int node, std::vector<int>& patch_nodes,
                                     std::vector<Eigen::Vector3d>& weights) const {
  assert(model_->nodalPressure() && "the volumetric patches exist for nodal pressure only");
  assemble();  // the rotated gradients
  const size_t r = static_cast<size_t>(node);
  patch_nodes.assign(patch_nodes_.begin() + patch_offsets_[r],
                     patch_nodes_.begin() + patch_offsets_[r + 1]);
  weights.assign(patch_nodes.size(), Eigen::Vector3d::Zero());
  for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
    const size_t t = static_cast<size_t>(node_entries_[static_cast<size_t>(k)] / 4);
    const double quarter_volume = 0.25 * model_->tetRestData()[t].volume;
    for (size_t b = 0; b < 4; ++b) {
      weights[static_cast<size_t>(patch_slots_[4 * static_cast<size_t>(k) + b])] +=
          quarter_volume * rotated_gradients_[4 * t + b];
    }
  }
}

void SystemOperator::replaceModel(std::shared_ptr<const FemModel> model) {
  assert(&model->mesh() == &model_->mesh() && model->elementKind() == model_->elementKind() &&
         "replaceModel wants a model of the same mesh and elements");
  model_ = std::move(model);
  assembled_ = false;  // K holds the old material's mu and lambda
}

}  // namespace torsion
