#pragma once
// The inner loops of SystemOperator (system_operator.h) on plain arrays: assembling K's 3x3
// blocks per block row, and the block product A y. They are compiled twice, from one source
// (system_operator_kernels.inc): once for any x86-64 (SSE2) and, on x86-64, once with AVX2 and
// FMA (system_operator_kernels_avx2.cpp); SystemOperator picks the second at run time when the
// CPU has both. The paths round differently (FMA, vector sums), so their results agree to
// rounding, not bit for bit; each is identical for any thread count (every output is written by
// one row, summed in a fixed order).

namespace torsion::system_kernels {

/// One term of a tet10 block: coefficient (R gL_c)(R gL_d)^T, with gL the element's corner
/// (barycentric) gradients.
struct BlockTerm {
  int c = 0, d = 0;
  double coefficient = 0;
};

/// What the assembly reads and writes. Block row n owns slots [row_offsets[n], row_offsets[n+1]).
/// tet4 sums each slot's own terms: slot s takes the couplings slot_terms[slot_term_offsets[s]
/// ..], each 16 e + 4 a + b (element e's local nodes a, b), in ascending elements. tet10 walks
/// the row's element entries node_entries[node_offsets[n] ..] (N e + local node), entry k's
/// coupling to local node b landing in slot entry_slots[N k + b] (-1: stored by another row).
struct AssemblyInput {
  const int* row_offsets = nullptr;
  const int* slot_term_offsets = nullptr;
  const int* slot_terms = nullptr;
  const int* node_offsets = nullptr;
  const int* node_entries = nullptr;
  const int* entry_slots = nullptr;
  /// Rotated gradients, 4 x 3 doubles per element: tet4 R g_a (the shape gradients), tet10
  /// R gL_c (the corner gradients).
  const double* rotated = nullptr;
  const double* volumes = nullptr;  ///< V per element, m^3
  double mu = 0, lambda = 0;
  /// tet10: the terms of block (a, b) are terms[term_offsets[10 a + b] .. term_offsets[10 a + b
  /// + 1]), coefficients including the quadrature weight 1/4 (times V at assembly).
  const int* term_offsets = nullptr;
  const BlockTerm* terms = nullptr;
  double* blocks = nullptr;  ///< out: 9 doubles (column-major) per slot
  /// Factored tet4 Hessians (fem/factored_tet_hessian.h), 30 doubles per element: c_0..c_3, then
  /// w of the pairs (0,1) (0,2) (0,3) (1,2) (1,3) (2,3); with `shear` (mu, Pa) times the rest
  /// Laplacian sum of each slot, slot_laplacian[slot] (sum of V (g_a . g_b) over its terms).
  const double* factored = nullptr;
  const double* slot_laplacian = nullptr;
  double shear = 0;
  /// Factored tet4: blocks in the same pattern (9 doubles per slot) added to each, times
  /// `lagged_weight` (a hyperelastic step's stiffness damping); null: none.
  const double* lagged = nullptr;
  double lagged_weight = 0;
};

/// out_n = stiffness_scale (K y)_n + mass_scale m_n y_n for block rows n; K is stored as the upper
/// block triangle, the blocks left of row n's diagonal read transposed through lower_*.
struct ProductInput {
  const int* row_offsets = nullptr;
  const int* columns = nullptr;
  const double* blocks = nullptr;
  const int* lower_offsets = nullptr;
  const int* lower_slots = nullptr;
  const int* lower_columns = nullptr;
  const double* mass = nullptr;
  const double* y = nullptr;
  double* out = nullptr;
  double mass_scale = 0, stiffness_scale = 0;
};

/// The per-tet pass of a tet4 step (ImplicitStepper): F = Ds Bm, the rotation R = polar(F) by
/// the warm-started quaternion iteration of fem/polar_rotation.h (extractRotation, with its
/// arithmetic and stopping rule per tet), and the corotated forces and energy of
/// fem/corotated_element.h. Four tets at a time, each stopping on its own, so a tet's result does
/// not depend on which tets share its batch. Tets with det F <= 0 (inverted, or NaN) are only
/// flagged (needs_svd = 1); the caller redoes them with the SVD path.
struct Tet4ForceInput {
  const double* positions = nullptr;  ///< 3 per node, m
  const int* nodes = nullptr;         ///< 4 per tet
  const double* rest = nullptr;       ///< per tet: Bm (9, column-major), then V; stride 10
  double mu = 0, lambda = 0;
  int max_iterations = 20;
  double tolerance = 1e-6;              ///< rad
  double* quaternions = nullptr;        ///< in/out: x, y, z, w per tet (the last step's rotation)
  double* rotations = nullptr;          ///< out: R, 9 per tet, column-major
  double* forces = nullptr;             ///< out: 12 per tet, N (null: only R, q and the gradients)
  double* energy = nullptr;             ///< out: per tet, J (with the forces)
  double* volumetric_strain = nullptr;  ///< out if not null: tr(R^T F) - 3 per tet
  /// out if not null: R g_a for the tet's four shape gradients g_a (g_1..3 the rows of Bm, g_0
  /// minus their sum), 12 per tet: what the assembly of K reads (AssemblyInput::rotated), written
  /// here while R is at hand instead of by a second pass over the tets. Bit for bit what
  /// SystemOperator's own pass computes (Eigen's 3x3 product: rows 0 and 1 summed left to right,
  /// row 2 as p0 + (p1 + p2)).
  double* rotated_gradients = nullptr;
  unsigned char* needs_svd = nullptr;  ///< out: per tet
};

/// The stable neo-Hookean tet4 without the log term (fem/hyperelastic.h), four tets at a time:
/// energy V (mu/2 (I_C - 3) + lambda/2 (J - alpha)^2 - rest_energy), forces f_a = -V P g_a with
/// P = mu F + lambda (J - alpha) cof F, and, if `factors` is set, the factors of its exact Hessian
/// (fem/factored_tet_hessian.h: U'' = lambda, U' = lambda (J - alpha)). A tet whose J is below
/// `barrier_threshold` (the volume barrier acts on it; -infinity when it is off) or not a number
/// is only flagged (needs_scalar = 1): the caller redoes it with the barrier, element by element.
struct NeoHookeanTet4Input {
  const double* positions = nullptr;  ///< 3 per node, m
  const int* nodes = nullptr;         ///< 4 per tet
  const double* rest = nullptr;       ///< per tet: Bm (9, column-major), then V; stride 10
  double mu = 0, lambda = 0, alpha = 1, rest_energy = 0;  ///< StableNeoHookean's, Pa
  double barrier_threshold = 0;                           ///< J
  double* forces = nullptr;                               ///< out: 12 per tet, N
  double* energy = nullptr;                               ///< out: per tet, J
  /// out if not null: 30 per tet, FactoredTetHessian's layout (c_0..c_3, then w_ab at
  /// nodePairIndex(a, b)).
  double* factors = nullptr;
  unsigned char* needs_scalar = nullptr;  ///< out: per tet
};

struct KernelTable {
  const char* name;  ///< "sse2" or "avx2+fma"
  void (*tet4_rows)(const AssemblyInput&, int row_begin, int row_end);
  void (*tet10_rows)(const AssemblyInput&, int row_begin, int row_end);
  /// tet4 blocks from factored Hessians: K_ab = shear V (g_a . g_b) I + c_a c_b^T + [+-w]x, plus
  /// lagged_weight times the lagged block.
  void (*factored_rows)(const AssemblyInput&, int row_begin, int row_end);
  void (*block_product)(const ProductInput&, int row_begin, int row_end);
  void (*tet4_forces)(const Tet4ForceInput&, int tet_begin, int tet_end);
  void (*neo_hookean_tet4)(const NeoHookeanTet4Input&, int tet_begin, int tet_end);
};

/// The baseline x86-64 (or other architecture's default) build.
const KernelTable& genericKernels();
/// The AVX2 + FMA build; nullptr where it is not compiled in. Call only on a CPU with both.
const KernelTable* avx2Kernels();

}  // namespace torsion::system_kernels
