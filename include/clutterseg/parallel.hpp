// The one threading helper: rows of an image in parallel (OpenMP when available). Work per row must be
// independent so that the output is identical for any thread count.
#pragma once

#include <functional>

// Per-pixel row kernels are compiled for AVX2 and for plain x86-64 and picked when the library loads,
// so one build is fast on current CPUs and runs on any. No -march flag: Eigen's struct alignment (and
// so the ABI with PCL and other users) stays the default. No FMA: both versions give identical bits.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CLUTTERSEG_ROW_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define CLUTTERSEG_ROW_KERNEL
#endif

namespace clutterseg {

void parallel_for_rows(int rows, const std::function<void(int begin, int end)>& body);

// Sets the thread count for parallel_for_rows (0 = all cores).
void set_threads(int threads);

}  // namespace clutterseg
