#include "torsion/solve/parallel.h"

namespace torsion {

Parallel::Parallel(int threads)
    : threads_(threads > 0 ? threads : tbb::this_task_arena::max_concurrency()),
      arena_(std::make_unique<tbb::task_arena>(threads_)) {}

}  // namespace torsion
