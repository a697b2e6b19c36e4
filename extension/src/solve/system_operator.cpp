#include "torsion/solve/system_operator.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "system_operator_kernels.h"
#include "torsion/fem/factored_tet_hessian.h"
#include "torsion/fem/nodal_pressure.h"

namespace torsion {

namespace {
constexpr int kTetGrain = 512;
constexpr int kNodeGrain = 256;

bool cpuHasAvx2Fma() {
#if defined(TORSION_HAVE_AVX2_KERNELS) && (defined(__GNUC__) || defined(__clang__))
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
  return false;
#endif
}

// The best kernel build for this CPU, unless TORSION_KERNELS=sse2 asks for the baseline.
const system_kernels::KernelTable& bestKernels() {
  const char* forced = std::getenv("TORSION_KERNELS");
  const bool baseline = forced != nullptr && std::strcmp(forced, "sse2") == 0;
  const system_kernels::KernelTable* avx2 = system_kernels::avx2Kernels();
  if (!baseline && avx2 != nullptr && cpuHasAvx2Fma()) return *avx2;
  return system_kernels::genericKernels();
}
}  // namespace

SystemOperator::SystemOperator(std::shared_ptr<const FemModel> model, const Parallel& parallel)
    : model_(std::move(model)), parallel_(parallel) {
  const int elements = model_->elementCount();
  const int n_per = model_->nodesPerElement();
  const std::vector<int>& element_nodes = model_->elementNodes();
  nodes_per_element_ = n_per;
  kernels_ = &bestKernels();
  rotations_.assign(static_cast<size_t>(elements), Eigen::Matrix3d::Identity());
  // Four rest-frame gradients per element: the shape gradients of a tet4, the corner gradients
  // of a tet10 (its blocks are combinations of their products, buildTet10Terms()).
  rest_gradients_.resize(4 * static_cast<size_t>(elements));
  rotated_gradients_.resize(rest_gradients_.size());
  element_volumes_.resize(static_cast<size_t>(elements));
  for (size_t e = 0; e < static_cast<size_t>(elements); ++e) {
    if (model_->elementKind() == ElementKind::kTet10) {
      const QuadraticRestData& rest = model_->quadraticRestData()[e];
      std::copy(rest.corner_gradients.begin(), rest.corner_gradients.end(),
                rest_gradients_.begin() + static_cast<std::ptrdiff_t>(4 * e));
      element_volumes_[e] = rest.volume;
    } else {
      const TetRestData& rest = model_->tetRestData()[e];
      const std::array<Eigen::Vector3d, 4> g = shapeGradients(rest.rest_shape_inverse);
      std::copy(g.begin(), g.end(), rest_gradients_.begin() + static_cast<std::ptrdiff_t>(4 * e));
      element_volumes_[e] = rest.volume;
    }
  }
  if (model_->elementKind() == ElementKind::kTet10) buildTet10Terms();
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

SystemOperator::~SystemOperator() = default;

const char* SystemOperator::kernelPath() const {
  return kernels_->name;
}

const char* SystemOperator::bestKernelPath() {
  return bestKernels().name;
}

void SystemOperator::useBaselineKernels(bool baseline) {
  kernels_ = baseline ? &system_kernels::genericKernels() : &bestKernels();
  assembled_ = false;  // K as the chosen build computes it
}

void SystemOperator::buildTet10Terms() {
  // K_ab = V sum_q (1/4) [mu (g_qa . g_qb) I + ...] with g_qa = sum_c alpha[q][a][c] grad L_c,
  // so every sum_q g_qa g_qb^T is sum over (c, d) of C_cd grad L_c grad L_d^T with
  // C_cd = (1/4) sum_q alpha[q][a][c] alpha[q][b][d]: the same C for every element. The zero
  // coefficients are exact (alpha is sparse), so they are left out.
  const Tet10GradientCoefficients& alpha = quadraticGradientCoefficients();
  term_offsets_.assign(1, 0);
  terms_.clear();
  for (size_t a = 0; a < 10; ++a) {
    for (size_t b = 0; b < 10; ++b) {
      for (int c = 0; c < 4; ++c) {
        for (int d = 0; d < 4; ++d) {
          double coefficient = 0;
          for (size_t q = 0; q < kTet10QuadraturePoints; ++q)
            coefficient +=
                alpha[q][a][static_cast<size_t>(c)] * alpha[q][b][static_cast<size_t>(d)];
          if (coefficient != 0.0) terms_.push_back({c, d, coefficient / kTet10QuadraturePoints});
        }
      }
      term_offsets_.push_back(static_cast<int>(terms_.size()));
    }
  }
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
  buildSlotTerms();
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

void SystemOperator::buildSlotTerms() {
  // Each slot's couplings N (N e + a) + b, from its row's entries in order: ascending elements.
  const int N = nodes_per_element_;
  slot_term_offsets_.assign(block_columns_.size() + 1, 0);
  for (int slot : entry_slots_)
    if (slot >= 0) ++slot_term_offsets_[static_cast<size_t>(slot) + 1];
  for (size_t s = 0; s + 1 < slot_term_offsets_.size(); ++s)
    slot_term_offsets_[s + 1] += slot_term_offsets_[s];
  slot_terms_.assign(static_cast<size_t>(slot_term_offsets_.back()), -1);
  std::vector<int> fill(slot_term_offsets_.begin(), slot_term_offsets_.end() - 1);
  for (size_t k = 0; k < node_entries_.size(); ++k) {
    for (int b = 0; b < N; ++b) {
      const int slot = entry_slots_[static_cast<size_t>(N) * k + static_cast<size_t>(b)];
      if (slot >= 0)
        slot_terms_[static_cast<size_t>(fill[static_cast<size_t>(slot)]++)] =
            N * node_entries_[k] + b;
    }
  }
  if (N != 4) return;
  slot_laplacian_.assign(block_columns_.size(), 0.0);
  for (size_t s = 0; s < block_columns_.size(); ++s) {
    for (int t = slot_term_offsets_[s]; t < slot_term_offsets_[s + 1]; ++t) {
      const int term = slot_terms_[static_cast<size_t>(t)];
      const size_t e = static_cast<size_t>(term >> 4);
      const size_t a = static_cast<size_t>((term >> 2) & 3), b = static_cast<size_t>(term & 3);
      slot_laplacian_[s] +=
          element_volumes_[e] * rest_gradients_[4 * e + a].dot(rest_gradients_[4 * e + b]);
    }
  }
}

void SystemOperator::setElementStiffnesses(const ElementStiffnesses* stiffnesses) {
  assert((stiffnesses == nullptr ||
          (model_->elementKind() == ElementKind::kTet10
               ? stiffnesses->tet10.size()
               : stiffnesses->tet4.size() + stiffnesses->factored_tet4.size()) ==
              static_cast<size_t>(model_->elementCount())) &&
         "one element stiffness of the model's element kind per element");
  element_stiffnesses_ = stiffnesses;
  assembled_ = false;
}

void SystemOperator::setLaggedStiffness(const std::vector<Eigen::Matrix3d>* blocks, double weight) {
  if (blocks == nullptr && lagged_blocks_ == nullptr) return;  // K as it was
  lagged_blocks_ = blocks;
  lagged_weight_ = weight;
  assembled_ = false;
}

void SystemOperator::multiplyBlocks(const std::vector<Eigen::Matrix3d>& blocks,
                                    const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  out.resize(y.size());
  system_kernels::ProductInput in = productInput(y, out, 0.0, 1.0);
  in.blocks = blocks.data()->data();
  parallel_.forRange(model_->nodeCount(), kNodeGrain,
                     [&](int begin, int end) { kernels_->block_product(in, begin, end); });
}

template <typename Stiffness>
void SystemOperator::assembleElementStiffnesses(const std::vector<Stiffness>& stiffness) const {
  constexpr int N = Stiffness::RowsAtCompileTime / 3;  // nodes per element
  assert(N == nodes_per_element_ && "element stiffnesses of the model's element kind");
  // Each block sums its own terms (elements ascending) in registers and is written once.
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    for (int s = row_offsets_[static_cast<size_t>(begin)];
         s < row_offsets_[static_cast<size_t>(end)]; ++s) {
      Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
      for (int t = slot_term_offsets_[static_cast<size_t>(s)];
           t < slot_term_offsets_[static_cast<size_t>(s) + 1]; ++t) {
        const int term = slot_terms_[static_cast<size_t>(t)];
        const int a = (term / N) % N, b = term % N;
        sum += stiffness[static_cast<size_t>(term / (N * N))].template block<3, 3>(3 * a, 3 * b);
      }
      if (lagged_blocks_ != nullptr)
        sum += lagged_weight_ * (*lagged_blocks_)[static_cast<size_t>(s)];
      block_values_[static_cast<size_t>(s)] = sum;
    }
  });
}

void SystemOperator::assembleFactoredHessians(const std::vector<FactoredTetHessian>& hessians,
                                              double shear) const {
  assert(nodes_per_element_ == 4 && "factored Hessians are tet4's");
  static_assert(sizeof(FactoredTetHessian) == 30 * sizeof(double), "c_0..c_3 then w, no padding");
  // Each block sums its own terms (elements ascending) and is written once, as the corotated
  // assembly's; its terms come from the factors (fem/factored_tet_hessian.h).
  system_kernels::AssemblyInput in;
  in.row_offsets = row_offsets_.data();
  in.slot_term_offsets = slot_term_offsets_.data();
  in.slot_terms = slot_terms_.data();
  in.factored = hessians.data()->c[0].data();
  in.slot_laplacian = slot_laplacian_.data();
  in.shear = shear;
  in.blocks = block_values_.data()->data();
  if (lagged_blocks_ != nullptr) {
    in.lagged = lagged_blocks_->data()->data();
    in.lagged_weight = lagged_weight_;
  }
  parallel_.forRange(model_->nodeCount(), kNodeGrain,
                     [&](int begin, int end) { kernels_->factored_rows(in, begin, end); });
}

void SystemOperator::assemble() const {
  if (assembled_) return;
  if (element_stiffnesses_ != nullptr) {
    if (model_->elementKind() == ElementKind::kTet10) {
      assembleElementStiffnesses(element_stiffnesses_->tet10);
    } else if (!element_stiffnesses_->factored_tet4.empty()) {
      assembleFactoredHessians(element_stiffnesses_->factored_tet4,
                               element_stiffnesses_->factored_shear);
    } else {
      assembleElementStiffnesses(element_stiffnesses_->tet4);
    }
    // (The lagged blocks are added by the assembly itself, in the same pass.)
    for (const SlotBlock& addition : stiffness_additions_)
      block_values_[static_cast<size_t>(addition.slot)] += addition.block;
    assembled_ = true;
    return;
  }
  const double mu = model_->material().mu();
  // With nodal pressure the blocks hold the deviatoric part only (nodal_pressure.h): the same
  // formula with lambda replaced by -2 mu / 3; the volumetric part is applied in factored form.
  const double lambda = model_->nodalPressure() ? -2.0 * mu / 3.0 : model_->material().lambda();
  // Pass 1, per element: the four rotated gradients (unless the force pass wrote them).
  if (!gradients_current_) {
    parallel_.forRange(model_->elementCount(), kTetGrain, [&](int begin, int end) {
      for (size_t e = static_cast<size_t>(begin); e < static_cast<size_t>(end); ++e)
        for (size_t c = 0; c < 4; ++c)
          rotated_gradients_[4 * e + c].noalias() = rotations_[e] * rest_gradients_[4 * e + c];
    });
    gradients_current_ = true;
  }
  // Pass 2, per block row: tet4 K_ab = V (mu (g_a . g_b) I + mu (R g_b)(R g_a)^T +
  // lambda (R g_a)(R g_b)^T) for every element of the row's node a (the rest-frame block rotated,
  // R Ke_ab R^T); tet10 the same integrated over the element (buildTet10Terms()).
  system_kernels::AssemblyInput in;
  in.row_offsets = row_offsets_.data();
  in.slot_term_offsets = slot_term_offsets_.data();
  in.slot_terms = slot_terms_.data();
  in.node_offsets = node_offsets_.data();
  in.node_entries = node_entries_.data();
  in.entry_slots = entry_slots_.data();
  in.rotated = rotated_gradients_.data()->data();
  in.volumes = element_volumes_.data();
  in.mu = mu;
  in.lambda = lambda;
  in.term_offsets = term_offsets_.data();
  in.terms = terms_.data();
  in.blocks = block_values_.data()->data();
  const bool tet10 = model_->elementKind() == ElementKind::kTet10;
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    if (tet10) {
      kernels_->tet10_rows(in, begin, end);
    } else {
      kernels_->tet4_rows(in, begin, end);
    }
  });
  for (const SlotBlock& addition : stiffness_additions_)
    block_values_[static_cast<size_t>(addition.slot)] += addition.block;
  assembled_ = true;
}

void SystemOperator::setStiffnessAdditions(std::vector<SlotBlock> additions) {
  if (additions.empty() && stiffness_additions_.empty()) return;  // K as it was
  stiffness_additions_ = std::move(additions);
  assembled_ = false;
}

int SystemOperator::blockSlot(int row, int column) const {
  const auto begin = block_columns_.begin() + row_offsets_[static_cast<size_t>(row)];
  const auto end = block_columns_.begin() + row_offsets_[static_cast<size_t>(row) + 1];
  const auto at = std::lower_bound(begin, end, column);
  return at != end && *at == column ? static_cast<int>(at - block_columns_.begin()) : -1;
}

void SystemOperator::rotateGradients(int element) {
  const size_t e = static_cast<size_t>(element);
  for (size_t c = 0; c < 4; ++c)
    rotated_gradients_[4 * e + c].noalias() = rotations_[e] * rest_gradients_[4 * e + c];
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

system_kernels::ProductInput SystemOperator::productInput(const Eigen::VectorXd& y,
                                                          Eigen::VectorXd& out, double mass_scale,
                                                          double stiffness_scale) const {
  system_kernels::ProductInput in;
  in.row_offsets = row_offsets_.data();
  in.columns = block_columns_.data();
  in.blocks = block_values_.data()->data();
  in.lower_offsets = lower_offsets_.data();
  in.lower_slots = lower_slots_.data();
  in.lower_columns = lower_columns_.data();
  in.mass = model_->nodeMasses().data();
  in.y = y.data();
  in.out = out.data();
  in.mass_scale = mass_scale;
  in.stiffness_scale = stiffness_scale;
  return in;
}

void SystemOperator::apply(const Eigen::VectorXd& y, Eigen::VectorXd& out, double mass_scale,
                           double stiffness_scale) const {
  assemble();
  out.resize(y.size());
  const bool nodal_pressure = model_->nodalPressure();
  if (nodal_pressure) nodalPressureIncrements(y);
  const system_kernels::ProductInput in = productInput(y, out, mass_scale, stiffness_scale);
  parallel_.forRange(model_->nodeCount(), kNodeGrain, [&](int begin, int end) {
    kernels_->block_product(in, begin, end);
    if (!nodal_pressure) return;
    for (int row = begin; row < end; ++row) {
      // K_vol y at this node: sum over its tets of V_e dpbar_e R_e g_a
      const size_t r = static_cast<size_t>(row);
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int k = node_offsets_[r]; k < node_offsets_[r + 1]; ++k) {
        const int entry = node_entries_[static_cast<size_t>(k)];
        sum.noalias() += tet_scalars_[static_cast<size_t>(entry / 4)] *
                         rotated_gradients_[static_cast<size_t>(entry)];
      }
      out.segment<3>(3 * row) += stiffness_scale * sum;
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
}

void SystemOperator::multiplyFromNodes(const Eigen::VectorXd& y, const std::vector<int>& nodes,
                                       Eigen::VectorXd& out) const {
  if (model_->nodalPressure()) {
    multiply(y, out);  // it couples rows beyond the block pattern
    return;
  }
  assemble();
  // A row with no coupled node in `nodes` sums +0 products only: +0, as in the full product.
  out.setZero(y.size());
  const int n = model_->nodeCount();
  row_marks_.resize(static_cast<size_t>(n), 0);
  marked_rows_.clear();
  auto mark = [&](int row) {
    if (row_marks_[static_cast<size_t>(row)] != 0) return;
    row_marks_[static_cast<size_t>(row)] = 1;
    marked_rows_.push_back(row);
  };
  for (int node : nodes) {
    const size_t r = static_cast<size_t>(node);
    for (int s = row_offsets_[r]; s < row_offsets_[r + 1]; ++s)  // includes the node itself
      mark(block_columns_[static_cast<size_t>(s)]);
    for (int l = lower_offsets_[r]; l < lower_offsets_[r + 1]; ++l)
      mark(lower_columns_[static_cast<size_t>(l)]);
  }
  const system_kernels::ProductInput in =
      productInput(y, out, mass_coefficient_, stiffness_coefficient_);
  for (int row : marked_rows_) {
    kernels_->block_product(in, row, row + 1);  // the same kernel, row by row: the same bits
    row_marks_[static_cast<size_t>(row)] = 0;
  }
}

void SystemOperator::multiplyStiffness(const Eigen::VectorXd& y, Eigen::VectorXd& out) const {
  apply(y, out, 0.0, 1.0);
}

void SystemOperator::multiplyStiffnessRows(const Eigen::VectorXd& y, const std::vector<int>& rows,
                                           Eigen::VectorXd& out) const {
  if (model_->nodalPressure()) {
    multiplyStiffness(y, out);  // its rows need every tet's pressure increment
    return;
  }
  assemble();
  out.resize(y.size());
  const system_kernels::ProductInput in = productInput(y, out, 0.0, 1.0);
  for (int row : rows)
    kernels_->block_product(in, row, row + 1);  // the same kernel, row by row: the same bits
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

void SystemOperator::takeStiffnessBlocks(std::vector<Eigen::Matrix3d>& blocks) {
  assemble();
  blocks.swap(block_values_);
  block_values_.resize(blocks.size());  // every assembly writes every block
  assembled_ = false;
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
