// Labels for pixels without depth that an object encloses (include/clutterseg/holes.hpp).
#include "clutterseg/holes.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>

namespace clutterseg {
namespace {

// A pixel that can take a label: no measurement and no label yet.
inline bool hole(float d, int label) { return !(d > 0) && label == 0; }

}  // namespace

int fill_depth_holes(cv::Mat& object_labels, const cv::Mat& depth, std::vector<Object>& objects, int max_run) {
  CV_Assert(object_labels.type() == CV_32S && depth.type() == CV_32F && object_labels.size() == depth.size());
  if (max_run <= 0) return 0;
  const int rows = depth.rows, cols = depth.cols, m = static_cast<int>(objects.size());
  std::vector<uchar> takes(static_cast<size_t>(m) + 1, 0);  // objects that may take pixels
  for (int k = 1; k <= m; ++k) takes[static_cast<size_t>(k)] = !objects[static_cast<size_t>(k - 1)].support &&
                                                              !objects[static_cast<size_t>(k - 1)].background;
  // Holes in a byte mask (the scans below skip eight measured pixels at a time).
  cv::Mat mask(rows, cols, CV_8U);
  int holes = 0;
  for (int y = 0; y < rows; ++y) {
    const float* d = depth.ptr<float>(y);
    const int* l = object_labels.ptr<int>(y);
    uchar* h = mask.ptr<uchar>(y);
    for (int x = 0; x < cols; ++x) h[x] = hole(d[x], l[x]);
  }
  // The label each hole gets: along its row first, then along its column; conflicts stay 0. Read from
  // the labels before any fill, so the result does not depend on the order of the scans.
  cv::Mat fill(rows, cols, CV_32S, cv::Scalar(0));
  std::vector<uchar> row_filled(static_cast<size_t>(rows), 0);  // the last pass skips the other rows
  const auto candidate = [&](int a, int b) { return a > 0 && a == b && a <= m && takes[static_cast<size_t>(a)] ? a : 0; };
  for (int y = 0; y < rows; ++y) {
    const uchar* h = mask.ptr<uchar>(y);
    const int* l = object_labels.ptr<int>(y);
    int* f = fill.ptr<int>(y);
    int x = 0;
    while (x < cols) {
      if (x + 8 <= cols) {
        std::uint64_t word;
        std::memcpy(&word, h + x, 8);
        if (word == 0) { x += 8; continue; }
      }
      if (!h[x]) { ++x; continue; }
      const int begin = x;
      while (x < cols && h[x]) ++x;
      if (begin > 0 && x < cols && x - begin <= max_run) {
        const int k = candidate(l[begin - 1], l[x]);
        if (k) {
          std::fill(f + begin, f + x, k);
          row_filled[static_cast<size_t>(y)] = 1;
        }
      }
    }
  }
  // Columns: a run starts at a hole whose upper neighbour is none; walk down at most max_run + 1 pixels.
  for (int y = 1; y < rows; ++y) {
    const uchar* h = mask.ptr<uchar>(y);
    const uchar* above = mask.ptr<uchar>(y - 1);
    int x = 0;
    while (x < cols) {
      if (x + 8 <= cols) {
        std::uint64_t word;
        std::memcpy(&word, h + x, 8);
        if (word == 0) { x += 8; continue; }
      }
      if (!h[x] || above[x]) { ++x; continue; }
      int end = y;
      while (end < rows && end - y <= max_run && mask.at<uchar>(end, x)) ++end;
      if (end < rows && end - y <= max_run) {
        const int k = candidate(object_labels.at<int>(y - 1, x), object_labels.at<int>(end, x));
        if (k)
          for (int yy = y; yy < end; ++yy) {
            int& f = fill.at<int>(yy, x);
            f = f == 0 || f == k ? k : -1;  // two objects claim it: nobody's
            row_filled[static_cast<size_t>(yy)] = 1;
          }
      }
      ++x;
    }
  }
  for (int y = 0; y < rows; ++y) {
    if (!row_filled[static_cast<size_t>(y)]) continue;
    const int* f = fill.ptr<int>(y);
    int* l = object_labels.ptr<int>(y);
    for (int x = 0; x < cols; ++x)
      if (f[x] > 0) {
        l[x] = f[x];
        ++objects[static_cast<size_t>(f[x] - 1)].pixel_count;
        ++holes;
      }
  }
  return holes;
}

}  // namespace clutterseg
