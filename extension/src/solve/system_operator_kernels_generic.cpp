// The kernels for any CPU of the target architecture (baseline x86-64: SSE2).
#include "system_operator_kernels.h"

namespace torsion::system_kernels {
namespace generic {
#define TORSION_KERNEL_TABLE kTable
#include "system_operator_kernels.inc"
#undef TORSION_KERNEL_TABLE
}  // namespace generic

const KernelTable& genericKernels() {
  return generic::kTable;
}

#ifndef TORSION_HAVE_AVX2_KERNELS
const KernelTable* avx2Kernels() {
  return nullptr;
}
#endif

}  // namespace torsion::system_kernels
