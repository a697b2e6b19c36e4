#include "torsion/solve/parallel.h"

#include <tbb/info.h>

#include <algorithm>

namespace torsion {

int Parallel::usableThreads(int requested) {
  // TBB never runs more workers than the machine has cores, whatever the arena asks for.
  const int cores = tbb::info::default_concurrency();
  return requested > 0 ? std::min(requested, cores) : cores;
}

Parallel::Parallel(int threads)
    : threads_(usableThreads(threads)), arena_(std::make_unique<tbb::task_arena>(threads_)) {}

}  // namespace torsion
