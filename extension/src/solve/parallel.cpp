#include "torsion/solve/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
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

struct Parallel::Arena {
  explicit Arena(int threads) : arena(threads) {}
  tbb::task_arena arena;
};

Parallel::Parallel(int threads)
    : threads_(usableThreads(threads)), arena_(std::make_unique<Arena>(threads_)) {}

Parallel::~Parallel() = default;

void Parallel::splitRange(int n, int grain, ChunkCall call, void* fn) const {
  split_calls_.fetch_add(1, std::memory_order_relaxed);
  arena_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<int>(0, n, static_cast<std::size_t>(grain)),
                      [&](const tbb::blocked_range<int>& r) { call(fn, r.begin(), r.end()); });
  });
}

}  // namespace torsion
