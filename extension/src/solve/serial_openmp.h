#pragma once
// CHOLMOD runs on the thread that calls it, with no OpenMP threads of its own.
//
// Debian's SuiteSparse is built with OpenMP, and CHOLMOD's supernodal factorisation opens a
// parallel region around each supernode's small loops (clearing and scattering a few hundred
// entries), with a thread count fixed when SuiteSparse was built. Every region wakes and parks
// that many threads: measured on 2 cores, 57 % of a factorisation's time was the kernel waking
// them, and the St-Venant validation tests ran 1.7 to 4 times longer with them
// (docs/performance.md, "The direct solver"). They would also run beside the haptic loop, outside
// TORSION_THREADS. The library's parallelism is its own (solve/parallel.h): CHOLMOD's is turned
// off for the calls the library makes, on the calling thread only.
namespace torsion::detail {

// For its lifetime, OpenMP parallel regions opened on this thread run on this thread alone
// (the thread's max-active-levels ICV at 0, its value restored at the end). The ICV belongs to
// the thread's OpenMP data environment, so other threads, the caller's own OpenMP code outside
// the scope included, are untouched. Without an OpenMP runtime in the process it does nothing.
class SerialOpenMpScope {
 public:
  SerialOpenMpScope();
  ~SerialOpenMpScope();
  SerialOpenMpScope(const SerialOpenMpScope&) = delete;
  SerialOpenMpScope& operator=(const SerialOpenMpScope&) = delete;

 private:
  int saved_levels_ = -1;  // -1: no runtime, nothing to restore
};

}  // namespace torsion::detail
