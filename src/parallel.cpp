#include "clutterseg/parallel.hpp"

#include <atomic>
#include <exception>
#include <opencv2/core/utility.hpp>

#ifdef _OPENMP
#include <omp.h>
#endif

namespace clutterseg {

void set_threads(int threads) {
  // OpenCV's calls here (median, Gaussian, components) are short; its pool's idle threads spin and
  // took the cores our OpenMP rows needed (2 threads ran 4x slower than 1), so OpenCV stays serial.
  cv::setNumThreads(1);
#ifdef _OPENMP
  omp_set_num_threads(threads > 0 ? threads : omp_get_num_procs());
#else
  (void)threads;
#endif
}

void parallel_for_rows(int rows, const std::function<void(int, int)>& body) {
  // Blocks of rows amortise the call; the split never changes what each row computes.
  constexpr int kBlock = 16;
  const int blocks = (rows + kBlock - 1) / kBlock;
  // An exception may not leave an OpenMP region (the process would terminate): the first one is kept,
  // the remaining blocks are skipped, and it is thrown again on the calling thread.
  std::exception_ptr failure;
  std::atomic<bool> failed{false};
#pragma omp parallel for schedule(static)
  for (int b = 0; b < blocks; ++b) {
    if (failed.load(std::memory_order_relaxed)) continue;
    const int begin = b * kBlock;
    const int end = begin + kBlock < rows ? begin + kBlock : rows;
    try {
      body(begin, end);
    } catch (...) {
#pragma omp critical(clutterseg_parallel_failure)
      if (!failure) failure = std::current_exception();
      failed.store(true, std::memory_order_relaxed);
    }
  }
  if (failure) std::rethrow_exception(failure);
}

}  // namespace clutterseg
