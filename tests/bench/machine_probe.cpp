// machine_probe: the two ceilings of a roofline on this machine, per core and for all cores:
// floating-point throughput (GFLOP/s, double precision) and memory bandwidth (GB/s, a STREAM-like
// triad). Prints one JSON line. docs/performance.md ("Roofline") puts each stage of a step
// against these.
//
//   build/tests/bench/machine_probe [--threads N] [--triad-mb MB]
//
// Throughput is measured three ways, because the library is compiled for baseline x86-64
// (SSE2: 2 doubles per instruction, no FMA) unless the build adds -march flags:
//   - sse2:   independent multiply-add chains of 2-double vectors, what our compiled kernels can
//             reach at best;
//   - avx2_fma / avx512_fma: fused multiply-add on 4 / 8 doubles (if the CPU has them), the
//             machine's peak.
// Bandwidth: a[i] = b[i] + s c[i] over arrays far larger than the last-level cache (memory) and
// over arrays that fit in L2 (the cache level our 8332-tet working set lives in), counting 24
// bytes per element (STREAM's convention: the write-allocate read is not counted).
// Every rate is work over each thread's own CPU time (CLOCK_THREAD_CPUTIME_ID), summed over the
// threads: on a machine shared with other jobs that is what a core does while it runs us, not
// how often the scheduler lets us run.

#include <immintrin.h>
#include <time.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

namespace {

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

constexpr int kChains = 12;  // independent accumulators: more than latency x ports

double sse2Flops(long iterations) {
  __m128d acc[kChains];
  for (int k = 0; k < kChains; ++k)
    acc[k] = _mm_set1_pd(1.0 + 1e-3 * k);
  const __m128d a = _mm_set1_pd(0.999999), b = _mm_set1_pd(1e-7);
  for (long i = 0; i < iterations; ++i) {
    for (int k = 0; k < kChains; ++k)
      acc[k] = _mm_add_pd(_mm_mul_pd(acc[k], a), b);
  }
  __m128d sum = acc[0];
  for (int k = 1; k < kChains; ++k)
    sum = _mm_add_pd(sum, acc[k]);
  double out[2];
  _mm_storeu_pd(out, sum);
  return out[0] + out[1];
}

__attribute__((target("avx2,fma"))) double avx2Flops(long iterations) {
  __m256d acc[kChains];
  for (int k = 0; k < kChains; ++k)
    acc[k] = _mm256_set1_pd(1.0 + 1e-3 * k);
  const __m256d a = _mm256_set1_pd(0.999999), b = _mm256_set1_pd(1e-7);
  for (long i = 0; i < iterations; ++i) {
    for (int k = 0; k < kChains; ++k)
      acc[k] = _mm256_fmadd_pd(acc[k], a, b);
  }
  __m256d sum = acc[0];
  for (int k = 1; k < kChains; ++k)
    sum = _mm256_add_pd(sum, acc[k]);
  double out[4];
  _mm256_storeu_pd(out, sum);
  return out[0] + out[1] + out[2] + out[3];
}

__attribute__((target("avx512f"))) double avx512Flops(long iterations) {
  __m512d acc[kChains];
  for (int k = 0; k < kChains; ++k)
    acc[k] = _mm512_set1_pd(1.0 + 1e-3 * k);
  const __m512d a = _mm512_set1_pd(0.999999), b = _mm512_set1_pd(1e-7);
  for (long i = 0; i < iterations; ++i) {
    for (int k = 0; k < kChains; ++k)
      acc[k] = _mm512_fmadd_pd(acc[k], a, b);
  }
  __m512d sum = acc[0];
  for (int k = 1; k < kChains; ++k)
    sum = _mm512_add_pd(sum, acc[k]);
  double out[8];
  _mm512_storeu_pd(out, sum);
  return out[0] + out[1] + out[2] + out[3] + out[4] + out[5] + out[6] + out[7];
}

// Runs fn(iterations) on `threads` threads at once; returns GFLOP/s of all of them together
// (flops_per_iteration per call and iteration), best of 3.
template <class Fn>
double gflops(Fn fn, int threads, double flops_per_iteration) {
  const long iterations = 40'000'000;
  double best = 0;
  for (int rep = 0; rep < 3; ++rep) {
    std::vector<std::thread> pool;
    std::vector<double> sink(static_cast<size_t>(threads)), rate(sink.size());
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] {
        const double t0 = threadCpuSeconds();
        sink[static_cast<size_t>(t)] = fn(iterations);
        rate[static_cast<size_t>(t)] =
            iterations * flops_per_iteration / (threadCpuSeconds() - t0) * 1e-9;
      });
    }
    for (std::thread& th : pool)
      th.join();
    if (sink[0] == 12345.0) std::printf(" ");  // keep the result alive
    double total = 0;
    for (double r : rate)
      total += r;
    best = std::max(best, total);
  }
  return best;
}

// Triad over `bytes_per_array` per array and thread, `threads` threads each on its own arrays;
// GB/s of all threads together, best of `reps` passes after a warm-up.
double triadGBs(size_t bytes_per_array, int threads, int reps) {
  const size_t n = bytes_per_array / sizeof(double);
  std::vector<std::vector<double>> a(static_cast<size_t>(threads)), b(a.size()), c(a.size());
  std::vector<std::thread> init;
  for (int t = 0; t < threads; ++t) {
    init.emplace_back([&, t] {  // first touch by the thread that uses them
      a[static_cast<size_t>(t)].assign(n, 0.0);
      b[static_cast<size_t>(t)].assign(n, 1.0);
      c[static_cast<size_t>(t)].assign(n, 2.0);
    });
  }
  for (std::thread& th : init)
    th.join();
  double best = 0;
  const double s = 0.5;
  for (int rep = 0; rep <= reps; ++rep) {
    std::vector<std::thread> pool;
    std::vector<double> seconds(static_cast<size_t>(threads));
    for (int t = 0; t < threads; ++t) {
      pool.emplace_back([&, t] {
        const double t0 = threadCpuSeconds();
        double* __restrict ap = a[static_cast<size_t>(t)].data();
        const double* __restrict bp = b[static_cast<size_t>(t)].data();
        const double* __restrict cp = c[static_cast<size_t>(t)].data();
        const int inner = bytes_per_array < (8u << 20) ? 200 : 1;  // cache-sized: repeat
        for (int k = 0; k < inner; ++k) {
          for (size_t i = 0; i < n; ++i)
            ap[i] = bp[i] + s * cp[i];
          asm volatile("" ::"r"(ap) : "memory");
        }
        seconds[static_cast<size_t>(t)] = threadCpuSeconds() - t0;
      });
    }
    for (std::thread& th : pool)
      th.join();
    const int inner = bytes_per_array < (8u << 20) ? 200 : 1;
    double total = 0;
    for (double sec : seconds)
      total += 3.0 * static_cast<double>(bytes_per_array) * inner / sec * 1e-9;
    if (rep > 0) best = std::max(best, total);
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  int threads = static_cast<int>(std::thread::hardware_concurrency());
  double triad_mb = 800;  // per array: well beyond a 480 MiB last-level cache
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--threads")) threads = std::atoi(argv[i + 1]);
    if (!std::strcmp(argv[i], "--triad-mb")) triad_mb = std::atof(argv[i + 1]);
  }
  threads = std::max(threads, 1);
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  const bool avx512 = __builtin_cpu_supports("avx512f");
  // Flops per iteration: kChains vectors, 2 flops per lane (multiply + add).
  const double sse2_1 = gflops(sse2Flops, 1, kChains * 2 * 2.0);
  const double sse2_n = gflops(sse2Flops, threads, kChains * 2 * 2.0);
  const double avx2_1 = avx2 ? gflops(avx2Flops, 1, kChains * 4 * 2.0) : 0;
  const double avx2_n = avx2 ? gflops(avx2Flops, threads, kChains * 4 * 2.0) : 0;
  const double avx512_1 = avx512 ? gflops(avx512Flops, 1, kChains * 8 * 2.0) : 0;
  const double avx512_n = avx512 ? gflops(avx512Flops, threads, kChains * 8 * 2.0) : 0;
  const size_t big = static_cast<size_t>(triad_mb * 1e6) / std::max(threads, 1);
  const double mem_1 = triadGBs(static_cast<size_t>(triad_mb * 1e6), 1, 3);
  const double mem_n = triadGBs(big, threads, 3);
  const double l2_1 = triadGBs(256u << 10, 1, 3);  // 3 x 256 KiB: fits in L2
  const double l2_n = triadGBs(256u << 10, threads, 3);
  std::printf(
      "{\"threads\": %d, \"gflops_sse2_1\": %.2f, \"gflops_sse2_all\": %.2f, "
      "\"gflops_avx2_fma_1\": %.2f, \"gflops_avx2_fma_all\": %.2f, \"gflops_avx512_fma_1\": "
      "%.2f, \"gflops_avx512_fma_all\": %.2f, \"triad_memory_gbs_1\": %.2f, "
      "\"triad_memory_gbs_all\": %.2f, \"triad_l2_gbs_1\": %.2f, \"triad_l2_gbs_all\": %.2f, "
      "\"triad_mb_per_array\": %.0f}\n",
      threads, sse2_1, sse2_n, avx2_1, avx2_n, avx512_1, avx512_n, mem_1, mem_n, l2_1, l2_n,
      triad_mb);
  return 0;
}
