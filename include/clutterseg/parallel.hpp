// The one threading helper: rows of an image in parallel (OpenMP when available). Work per row must be
// independent so that the output is identical for any thread count.
#pragma once

#include <functional>

// Per-pixel row kernels are compiled for AVX-512 (x86-64-v4), AVX2 and plain x86-64 and picked when the
// library loads, so one build is fast on current CPUs and runs on any. No -march flag: Eigen's struct
// alignment (and so the ABI with PCL and other users) stays the default. No FMA contraction
// (-ffp-contract=off): every version gives identical bits. Kernels over short runs, and the hole-border
// mask, measured slower with 16-wide vectors (the scalar tail is longer, byte masks need packing):
// those are CLUTTERSEG_AVX2_KERNEL, without the AVX-512 version (docs/BENCHMARKS.md).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CLUTTERSEG_ROW_KERNEL __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#define CLUTTERSEG_AVX2_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define CLUTTERSEG_ROW_KERNEL
#define CLUTTERSEG_AVX2_KERNEL
#endif

namespace clutterseg {

void parallel_for_rows(int rows, const std::function<void(int begin, int end)>& body);

// Sets the thread count for parallel_for_rows (0 = all cores).
void set_threads(int threads);

}  // namespace clutterseg
