// Depth PNG reader: any bytes under a .png name give a CV_16UC1 image or clutterseg::Error.
#include <cstdlib>

#include "clutterseg/io.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = clutterseg::fuzz::write_input(data, size, ".png");
  try {
    const cv::Mat depth = clutterseg::read_depth_png(file);
    if (depth.type() != CV_16UC1 || depth.empty()) std::abort();  // the reader's promise
  } catch (const clutterseg::Error&) {
  }
  return 0;
}
