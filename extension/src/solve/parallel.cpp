#include "torsion/solve/parallel.h"

#include <tbb/info.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>

namespace torsion {

std::optional<int> threadsFromEnvironment() {
  const char* text = std::getenv(kThreadsVariable);
  // Digits only: strtol would also take leading blanks and a sign.
  if (text == nullptr || *text < '0' || *text > '9') return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (errno != 0 || *end != '\0' || value < 1 || value > kMaxThreads) return std::nullopt;
  return static_cast<int>(value);
}

int Parallel::usableThreads(int requested) {
  // TBB never runs more workers than the machine has cores, whatever the arena asks for.
  const int cores = tbb::info::default_concurrency();
  if (requested <= 0) requested = threadsFromEnvironment().value_or(cores);
  return std::min(requested, cores);
}

Parallel::Parallel(int threads)
    : threads_(usableThreads(threads)), arena_(std::make_unique<tbb::task_arena>(threads_)) {}

}  // namespace torsion
