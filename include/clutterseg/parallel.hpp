// The one threading helper: rows of an image in parallel (a small pool with sleeping helpers; no
// OpenMP runtime). Work per row must be independent so that the output is identical for any thread
// count. Cross-frame parallelism (throughput) is the Pipeline (pipeline.hpp).
#pragma once

#include <functional>

// Per-pixel row kernels are compiled for AVX-512 (x86-64-v4), AVX2 and plain x86-64 and picked when the
// library loads, so one build is fast on current CPUs and runs on any. No -march flag: Eigen's struct
// alignment (and so the ABI with PCL and other users) stays the default. No FMA contraction
// (-ffp-contract=off), so the versions give identical bits. CLUTTERSEG_AVX2_KERNEL leaves out the
// AVX-512 version: for kernels over short runs and the hole-border mask, which measured slower 16 wide
// (docs/BENCHMARKS.md), and for float sums vectorised with `omp simd reduction`, whose last bits depend
// on the vector width (AVX-512 machines then give the bits AVX2 machines give; a CPU without AVX2 may
// differ from both in those last bits).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CLUTTERSEG_ROW_KERNEL __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#define CLUTTERSEG_AVX2_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define CLUTTERSEG_ROW_KERNEL
#define CLUTTERSEG_AVX2_KERNEL
#endif

namespace clutterseg {

void parallel_for_rows(int rows, const std::function<void(int begin, int end)>& body);

// Sets the calling thread's thread count for parallel_for_rows: 1 = serial, N = up to N threads,
// 0 (the default) = the idle cores at each region but one (serial on a 2-core or a busy machine).
void set_threads(int threads);

// The threads the calling thread's next region would use (1 when it runs serially).
int region_threads();

// Cores no runnable task other than the caller uses right now (the caller's own counted as free; Linux:
// /proc/loadavg; all cores elsewhere). 0 or less when the machine is busy.
int free_cores();

}  // namespace clutterseg
