// A Segmenter keeps a frame's freed memory for the next frame (glibc), instead of handing it back to the
// kernel and page-faulting it in again (docs/BENCHMARKS.md: a quarter of the pre-segmentation's time).
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "clutterseg/segmenter.hpp"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

using namespace clutterseg;

TEST(Memory, FreedFrameBuffersStayInTheHeapForTheNextFrame) {
#if defined(__GLIBC__)
  const Segmenter segmenter;  // default Params: keep_freed_memory = true
  constexpr size_t kFrame = 32u << 20;  // more than a 640x480 frame's largest buffers together
  void* block = std::malloc(kFrame);
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kFrame);  // touched, as a frame's images are
  std::free(block);
  // Still in the heap as free space (glibc's default would have unmapped a block this large).
  EXPECT_GE(mallinfo2().fordblks, kFrame);
#else
  GTEST_SKIP() << "the allocator tuning is for glibc only";
#endif
}
