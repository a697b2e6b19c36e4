#pragma once
// The linearised backward-Euler system of one body at the current positions,
//   A = M (1 + dt alpha) + (dt^2 + dt beta) K,   K = sum over elements of Re Ke Re^T,
// with the rotations Re of this step. K is assembled once per step into 3x3 node blocks (block
// rows = nodes, a row holds the node and its element neighbours), so each CG product is a sparse
// block product instead of a pass over every element. Elements are the model's (tet4: 4 nodes,
// one point; tet10: 10 nodes, 4 quadrature points): the same assembly, templated on both. Measured
// on the 8332-tet twist (callgrind, docs/performance.md): a product takes 4.9x fewer instructions
// than the matrix-free tet loop did and assembling costs about three such loops, so it pays from
// four products per step on (a step at E = 1e5 takes about six; stiffer materials take more).
// Assembly runs per block row over the row node's tets in ascending order, so K and every
// product are identical for any thread count.
//
// The assembly and the product run in kernels on plain arrays
// (src/solve/system_operator_kernels.h), built twice: for baseline x86-64 and for AVX2 + FMA,
// chosen at run time (kernelPath()). tet10 blocks are combinations of the rotated corner-gradient
// products (R gL_c)(R gL_d)^T (one term for a corner-corner block, four for an edge-edge block)
// instead of one rank-2 update per quadrature point.
//
// Nodal pressure (tet4 with VolumetricStrain::kNodalAverage, fem/nodal_pressure.h): the blocks
// hold the deviatoric stiffness, and the volumetric part sum_n kappa V_n b_n b_n^T, which couples
// nodes two tets apart, is applied in its factored form in every product (three more passes:
// per tet, per node, per tet); diagonalBlocks() includes its diagonal.

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

#include "torsion/fem/factored_tet_hessian.h"
#include "torsion/fem/fem_model.h"
#include "torsion/fem/volume_barrier.h"
#include "torsion/solve/parallel.h"

namespace torsion {

namespace system_kernels {
struct KernelTable;
struct BlockTerm;
struct ProductInput;
}  // namespace system_kernels

/// Element stiffnesses (SystemOperator::setElementStiffnesses), one per element, in one member:
/// `tet4` (12x12) or `factored_tet4` (fem/factored_tet_hessian.h, with the shear modulus
/// `factored_shear`, Pa) for tet4 models, `tet10` (30x30) for tet10 models (the others empty).
struct ElementStiffnesses {
  std::vector<TetStiffness> tet4;
  std::vector<FactoredTetHessian> factored_tet4;
  double factored_shear = 0;
  std::vector<Tet10Stiffness> tet10;
};

class SystemOperator {
 public:
  SystemOperator(std::shared_ptr<const FemModel> model, const Parallel& parallel);
  ~SystemOperator();  // out of line: the kernel terms' type is private

  /// The rotation of every element for this step. Writing through mutableRotations() marks K stale;
  /// the next product or diagonalBlocks() call re-assembles it (products are not thread-safe
  /// with each other: one solver thread drives a body).
  const std::vector<Eigen::Matrix3d>& rotations() const { return rotations_; }
  std::vector<Eigen::Matrix3d>& mutableRotations() {
    assembled_ = false;
    gradients_current_ = false;
    return rotations_;
  }
  /// For a pass that computes the rotations itself (the tet4 force pass of ImplicitStepper) and
  /// can write the rotated gradients the assembly reads in the same pass: the rotations and the
  /// rotated gradients, 4 per element (index 4 e + a), rotated_gradients[4 e + a] = R_e g_a with
  /// g_a the element's rest gradients (tet4: the shape gradients, g_0 = -(sum of Bm's rows)).
  /// Marks K stale; the assembly then skips its own pass over the elements. The caller fills
  /// both for every element before the next product (rotateGradients() does one element).
  struct RotationOutputs {
    std::vector<Eigen::Matrix3d>& rotations;
    std::vector<Eigen::Vector3d>& rotated_gradients;
  };
  RotationOutputs mutableRotationsAndGradients() {
    assembled_ = false;
    gradients_current_ = true;
    return {rotations_, rotated_gradients_};
  }
  /// rotated_gradients[4 e + a] = rotations()[e] g_a for one element e.
  void rotateGradients(int element);
  /// A 3x3 block added to K's stored block at `slot` (blockSlot()).
  struct SlotBlock {
    int slot = -1;
    Eigen::Matrix3d block = Eigen::Matrix3d::Zero();
  };
  /// Blocks added to K after each assembly until replaced (the volume barrier's stiffness of the
  /// tets below its threshold, fem/volume_barrier.h): they enter every product, the diagonal
  /// blocks and stiffnessBlocks(). Added in the given order, so K stays deterministic.
  void setStiffnessAdditions(std::vector<SlotBlock> additions);
  /// Hyperelastic bodies (fem/hyperelastic.h; not owned, nullptr for the corotated assembly): K
  /// is assembled from these element stiffnesses, one (3N)x(3N) matrix per element (N nodes per
  /// element: the `tet4` member for tet4, `tet10` for tet10), instead of from the rotations, per
  /// block row over the row node's elements in ascending order (identical for any thread count).
  /// Marks K stale: call again whenever their values change.
  void setElementStiffnesses(const ElementStiffnesses* stiffnesses);
  /// Blocks in this operator's pattern (not owned; nullptr: none) added to K, times `weight`,
  /// by each assembly from element stiffnesses: a hyperelastic step's stiffness damping, lagged
  /// at the step's start.
  void setLaggedStiffness(const std::vector<Eigen::Matrix3d>* blocks, double weight);
  /// out = B y for blocks B in this operator's pattern (e.g. a copy of stiffnessBlocks()).
  void multiplyBlocks(const std::vector<Eigen::Matrix3d>& blocks, const Eigen::VectorXd& y,
                      Eigen::VectorXd& out) const;
  /// The slot of the stored block K(row, column), row <= column, or -1 when the pattern has none
  /// (the two nodes share no element).
  int blockSlot(int row, int column) const;
  /// The system coefficients: A = mass_coefficient M + stiffness_coefficient K.
  void setCoefficients(double mass_coefficient, double stiffness_coefficient);

  /// out = A y.
  void multiply(const Eigen::VectorXd& y, Eigen::VectorXd& out) const;
  /// out = A y for a y that is zero outside `nodes`: only the block rows coupled to those nodes
  /// are multiplied, the others are zero; bit for bit what multiply() gives (with nodal pressure
  /// or an added term it is multiply()). The projected CG's reference residual, where y holds
  /// the prescribed velocities alone, costs a few rows instead of a product.
  void multiplyFromNodes(const Eigen::VectorXd& y, const std::vector<int>& nodes,
                         Eigen::VectorXd& out) const;
  /// out = K y.
  void multiplyStiffness(const Eigen::VectorXd& y, Eigen::VectorXd& out) const;
  /// (K y) at the block rows `rows` only (out sized 3n, its other rows left as they are): bit for
  /// bit those rows of multiplyStiffness() (with nodal pressure it is multiplyStiffness()). The
  /// force on a few nodes costs their rows instead of a product.
  void multiplyStiffnessRows(const Eigen::VectorXd& y, const std::vector<int>& rows,
                             Eigen::VectorXd& out) const;
  /// out_i = scale * sum of the per-element values of node i (element_values[N e + a] belongs to
  /// node elementNodes()[N e + a], N nodes per element), summed over the node's elements in
  /// ascending order.
  void gather(const std::vector<Eigen::Vector3d>& element_values, double scale,
              Eigen::VectorXd& out) const;
  /// The 3x3 diagonal blocks of A (plus the added term's), one per node.
  void diagonalBlocks(std::vector<Eigen::Matrix3d>& blocks) const;

  // ---- The assembled matrix, for direct solvers (CholmodSolver) ----
  /// K for this step's rotations as upper-triangle 3x3 node blocks (assembled first if stale):
  /// block row n is slots [blockRowOffsets()[n], blockRowOffsets()[n + 1]), slot s holding
  /// K(n, blockColumns()[s]) in stiffnessBlocks()[s]; columns ascend from the diagonal block.
  /// With nodal pressure the blocks are the deviatoric part (the volumetric part:
  /// volumetricPatch()). The references stay valid for the operator's life.
  const std::vector<int>& blockRowOffsets() const { return row_offsets_; }
  const std::vector<int>& blockColumns() const { return block_columns_; }
  const std::vector<Eigen::Matrix3d>& stiffnessBlocks() const;
  /// stiffnessBlocks() moved into `blocks` (its old contents become this operator's storage, so
  /// a step that keeps K each step copies nothing); K is assembled again at the next use.
  void takeStiffnessBlocks(std::vector<Eigen::Matrix3d>& blocks);
  /// The assembly and the product run in kernels on plain arrays
  /// (src/solve/system_operator_kernels.h),
  // built twice: for baseline x86-64 and for AVX2 + FMA, chosen at run time (kernelPath()).
  // tet10 blocks are combinations of the rotated corner-gradient products (R gL_c)(R gL_d)^T
  // (one term for a corner-corner block, four for an edge-edge block) instead of one rank-2 update
  // per quadrature point.
  //
  // Nodal pressure (tet4) only: the volumetric stiffness is sum over nodes n of
  /// kappa / V_n w_n w_n^T, where w_n has one 3-vector per node a of n's patch (the nodes of n's
  /// tets), (w_n)_a = sum over n's tets e holding a of (V_e / 4) R_e g_a. Fills the patch's nodes
  /// (ascending) and w_n.
  void volumetricPatch(int node, std::vector<int>& patch_nodes,
                       std::vector<Eigen::Vector3d>& weights) const;

  const FemModel& model() const { return *model_; }
  /// Live edits (FemBody::setMaterial): the same mesh with another material. The node-tet tables,
  /// the block pattern and this step's rotations stay; K is re-assembled with the new material
  /// constants at the next product, and the masses are the new model's.
  void replaceModel(std::shared_ptr<const FemModel> model);
  /// The kernel build this operator runs: "avx2+fma" on a CPU with AVX2 and FMA (where the
  /// library was built for x86-64), else "sse2". The environment variable TORSION_KERNELS=sse2
  /// forces the baseline build for every operator created after it is set.
  const char* kernelPath() const;
  /// The build a new operator would choose on this machine.
  static const char* bestKernelPath();
  /// Switches this operator to the baseline build (true) or back to the best one (false); the
  /// paths agree to rounding (tests compare them).
  void useBaselineKernels(bool baseline);
  /// The chosen kernel build itself (src/solve/system_operator_kernels.h), for the implicit
  /// stepper's per-tet force pass.
  const system_kernels::KernelTable& kernels() const { return *kernels_; }
  double massCoefficient() const { return mass_coefficient_; }
  double stiffnessCoefficient() const { return stiffness_coefficient_; }

 private:
  // out_i = mass_scale m_i y_i + stiffness_scale (K y)_i
  void apply(const Eigen::VectorXd& y, Eigen::VectorXd& out, double mass_scale,
             double stiffness_scale) const;
  // The block product kernel's input over the stored pattern, for y into out (sized).
  system_kernels::ProductInput productInput(const Eigen::VectorXd& y, Eigen::VectorXd& out,
                                            double mass_scale, double stiffness_scale) const;
  void buildPattern();
  void buildSlotTerms();
  // tet_scalars_[e] = V_e dpbar_e(y), the volumetric stiffness's tet pressures for y.
  void nodalPressureIncrements(const Eigen::VectorXd& y) const;
  void addNodalPressureDiagonal(std::vector<Eigen::Matrix3d>& blocks) const;
  void buildPatches();
  // Fills block_values_ from this step's rotations (if stale).
  void assemble() const;
  // Fills block_values_ from element stiffnesses (12x12 or 30x30, one per element).
  template <typename Stiffness>
  void assembleElementStiffnesses(const std::vector<Stiffness>& stiffnesses) const;
  void assembleFactoredHessians(const std::vector<FactoredTetHessian>& hessians,
                                double shear) const;
  // tet10: the terms of every block (a, b) (system_kernels::BlockTerm), once per operator.
  void buildTet10Terms();

  std::shared_ptr<const FemModel> model_;
  const Parallel& parallel_;
  std::vector<Eigen::Matrix3d> rotations_;
  std::vector<SlotBlock> stiffness_additions_;
  const ElementStiffnesses* element_stiffnesses_ = nullptr;
  const std::vector<Eigen::Matrix3d>* lagged_blocks_ = nullptr;
  double lagged_weight_ = 0;
  double mass_coefficient_ = 1;
  double stiffness_coefficient_ = 0;

  int nodes_per_element_ = 4;
  // Node -> its elements: entry k of row n is N * element + local index, rows in node_offsets_.
  std::vector<int> node_entries_;
  std::vector<int> node_offsets_;
  // Block-sparse K, upper triangle: block row n spans [row_offsets_[n], row_offsets_[n + 1]) of
  // block_columns_ / block_values_, diagonal first; entry_slots_[N k + b] is where node entry k's
  // coupling to its element's local node b lands (-1 left of the diagonal); diagonal_slots_[n] is
  // K_nn.
  std::vector<int> row_offsets_;
  std::vector<int> block_columns_;
  std::vector<int> entry_slots_;
  std::vector<int> diagonal_slots_;
  // Slot s sums the couplings slot_terms_[slot_term_offsets_[s] ..], each N (N e + a) + b
  // (element e's local nodes a, b), ascending elements: the tet4 kernel and element stiffnesses.
  std::vector<int> slot_term_offsets_;
  std::vector<int> slot_terms_;
  // tet4, per slot: sum over its terms of V_e (g_a . g_b), the rest shape's Laplacian block that
  // the shear term of a factored Hessian scales (assembleFactoredHessians).
  std::vector<double> slot_laplacian_;
  // Upper-triangle storage: row n also reads the blocks (row r < n, column n) transposed; they
  // are lower_slots_[l] with r = lower_columns_[l], l in [lower_offsets_[n], lower_offsets_[n+1]).
  std::vector<int> lower_offsets_;
  std::vector<int> lower_slots_;
  std::vector<int> lower_columns_;
  mutable std::vector<Eigen::Matrix3d> block_values_;
  // Rest-frame gradients, four per element (tet4: grad N_a; tet10: the corner gradients grad L_c),
  // their rotations R_e g for this step (same index 4 e + c), and the element volumes.
  std::vector<Eigen::Vector3d> rest_gradients_;
  mutable std::vector<Eigen::Vector3d> rotated_gradients_;
  std::vector<double> element_volumes_;
  std::vector<int> term_offsets_;
  std::vector<system_kernels::BlockTerm> terms_;
  const system_kernels::KernelTable* kernels_ = nullptr;
  mutable bool assembled_ = false;
  // The rotated gradients match rotations_ (the assembly's first pass is not needed).
  mutable bool gradients_current_ = false;
  // tet4 node patches (for the nodal-pressure diagonal): row n's patch, the nodes of its tets
  // sorted, is patch_nodes_[patch_offsets_[n] ..]; patch_slots_[4 k + b] is where local node b of
  // node entry k's tet sits in its row's patch.
  std::vector<int> patch_offsets_, patch_nodes_, patch_slots_;
  // Nodal pressure scratch: per tet and per node scalars of one product.
  mutable std::vector<double> tet_scalars_, node_scalars_;
  // multiplyFromNodes() scratch: 1 for the rows it multiplies (all 0 between calls), and them.
  mutable std::vector<unsigned char> row_marks_;
  mutable std::vector<int> marked_rows_;
};

}  // namespace torsion
