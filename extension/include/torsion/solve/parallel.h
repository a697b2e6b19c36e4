#pragma once
// Threading for the solver kernels, on TBB. Kernels take index ranges [begin, end) so they can be
// split without new signatures. Results are identical for any thread count: loops write disjoint
// outputs, and sums are left to the callers, which add per-chunk results in a fixed order.
//
// TBB stays in parallel.cpp: its headers are some 100k preprocessed lines, 0.3 s (clang) to 1.1 s
// (gcc -O2) of compile time in every translation unit that includes this one (most of the
// library's and the tests').
// A split range reaches the caller's function through one indirect call per chunk.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <type_traits>

namespace torsion {

/// The environment variable that sets the default thread count (a request of 0), as
/// OMP_NUM_THREADS does for OpenMP programs: for runs side by side (a test suite, a Dask
/// fan-out, several simulations on one machine), each of which would otherwise take every core.
inline constexpr const char* kThreadsVariable = "TORSION_THREADS";
inline constexpr int kMaxThreads = 4096;

/// TORSION_THREADS as a count: nothing when it is unset or empty, or not a whole number from 1
/// to kMaxThreads (the command-line tool refuses such a value with a message; the library, which
/// has no one to tell, ignores it).
std::optional<int> threadsFromEnvironment();

class Parallel {
 public:
  /// threads <= 0: TORSION_THREADS when set, else as many as the machine has; more than it has:
  /// as many as it has.
  explicit Parallel(int threads = 0);
  ~Parallel();
  Parallel(const Parallel&) = delete;
  Parallel& operator=(const Parallel&) = delete;
  /// The threads a request gets: min(requested, cores); for requested <= 0, TORSION_THREADS
  /// (capped the same way) or all cores.
  static int usableThreads(int requested);

  int threads() const { return threads_; }

  /// Calls fn(begin, end) over [0, n) in chunks of at least `grain`.
  template <class Fn>
  void forRange(int n, int grain, Fn&& fn) const {
    if (threads_ == 1 || n <= grain) {
      if (n > 0) fn(0, n);
      return;
    }
    using Function = std::remove_reference_t<Fn>;
    splitRange(n, grain, &callChunk<Function>,
               const_cast<void*>(static_cast<const void*>(std::addressof(fn))));
  }

  /// How many forRange calls were split across threads so far (tests check that a parallel
  /// run really ran in parallel).
  std::int64_t splitCalls() const { return split_calls_.load(std::memory_order_relaxed); }

 private:
  using ChunkCall = void (*)(void* fn, int begin, int end);
  template <class Function>
  static void callChunk(void* fn, int begin, int end) {
    (*static_cast<Function*>(fn))(begin, end);
  }
  /// tbb::parallel_for over [0, n) in this object's arena, calling call(fn, begin, end).
  void splitRange(int n, int grain, ChunkCall call, void* fn) const;

  struct Arena;
  int threads_;
  std::unique_ptr<Arena> arena_;
  mutable std::atomic<std::int64_t> split_calls_{0};
};

}  // namespace torsion
