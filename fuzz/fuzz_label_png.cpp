// Label images for eval: the reader, then both metric families of a prediction against it (the label
// itself, and the label shifted by one pixel: many ids, partial overlaps) and the error breakdown.
#include <cstdlib>

#include "clutterseg/error_breakdown.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/metrics.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace clutterseg;
  const auto file = fuzz::write_input(data, size, ".png");
  cv::Mat labels;
  try {
    labels = read_label_png(file);
  } catch (const Error&) {
    return 0;
  }
  if (labels.type() != CV_32S) std::abort();
  cv::Mat shifted(labels.size(), CV_32S, cv::Scalar(0));
  if (labels.cols > 1) labels.colRange(0, labels.cols - 1).copyTo(shifted.colRange(1, labels.cols));
  for (const cv::Mat* pred : {&labels, &shifted}) {
    const FrameScores s = score_frame(labels, *pred);
    if (s.scored() && !(s.overlap_f >= 0 && s.overlap_f <= 1 && s.boundary_f >= 0 && s.boundary_f <= 1)) std::abort();
    if (pred == &labels && s.scored() && s.overlap_f != 1) std::abort();  // a perfect prediction scores 1
    error_breakdown(labels, *pred, s.matches);
  }
  return 0;
}
