// The kernels built with -mavx2 -mfma (extension/CMakeLists.txt, x86-64 only). Called only after
// the CPU was checked for both (SystemOperator).
#include <immintrin.h>

#include "system_operator_kernels.h"

#if !defined(__AVX2__) || !defined(__FMA__)
#error "compile this file with -mavx2 -mfma"
#endif

namespace torsion::system_kernels {
namespace avx2 {
#define TORSION_KERNEL_TABLE kTable
#include "system_operator_kernels.inc"
#undef TORSION_KERNEL_TABLE
}  // namespace avx2

const KernelTable* avx2Kernels() {
  return &avx2::kTable;
}

}  // namespace torsion::system_kernels
