#pragma once
// Threading for the solver kernels, on TBB. Kernels take index ranges [begin, end) so they can be
// split without new signatures. Results are identical for any thread count: loops write disjoint
// outputs, and sums use a fixed split into chunks whose partial sums are added in chunk order.

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <memory>

namespace torsion {

class Parallel {
 public:
  /// threads <= 0: as many as the machine has; more than it has: as many as it has.
  explicit Parallel(int threads = 0);
  /// The threads a request gets: min(requested, cores), all cores for requested <= 0.
  static int usableThreads(int requested);

  int threads() const { return threads_; }

  /// Calls fn(begin, end) over [0, n) in chunks of at least `grain`.
  template <class Fn>
  void forRange(int n, int grain, Fn&& fn) const {
    if (threads_ == 1 || n <= grain) {
      if (n > 0) fn(0, n);
      return;
    }
    arena_->execute([&] {
      tbb::parallel_for(tbb::blocked_range<int>(0, n, grain),
                        [&](const tbb::blocked_range<int>& r) { fn(r.begin(), r.end()); });
    });
  }

  /// Sum of fn(begin, end) over fixed chunks of `grain`, added in chunk order.
  template <class Fn>
  double sum(int n, int grain, Fn&& fn) const {
    if (threads_ == 1 || n <= grain) {
      // Same chunking as the parallel path, so the rounding is identical.
      double total = 0;
      for (int begin = 0; begin < n; begin += grain)
        total += fn(begin, std::min(n, begin + grain));
      return total;
    }
    const int chunks = (n + grain - 1) / grain;
    partial_.resize(static_cast<size_t>(chunks));
    forRange(chunks, 1, [&](int c0, int c1) {
      for (int c = c0; c < c1; ++c) {
        partial_[static_cast<size_t>(c)] = fn(c * grain, std::min(n, (c + 1) * grain));
      }
    });
    double total = 0;
    for (double p : partial_)
      total += p;
    return total;
  }

 private:
  int threads_;
  std::unique_ptr<tbb::task_arena> arena_;
  mutable std::vector<double> partial_;
};

}  // namespace torsion
