// The one threading helper: rows of an image in parallel (OpenMP when available). Work per row must be
// independent so that the output is identical for any thread count.
#pragma once

#include <functional>

namespace clutterseg {

void parallel_for_rows(int rows, const std::function<void(int begin, int end)>& body);

// Sets the thread count for parallel_for_rows (0 = all cores).
void set_threads(int threads);

}  // namespace clutterseg
