#include "clutterseg/smoothing.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

cv::Mat depth_to_metres(const cv::Mat& depth, const Camera& camera) {
  cv::Mat out(depth.size(), CV_32F);
  if (depth.type() == CV_16UC1) {
    depth.convertTo(out, CV_32F, camera.depth_unit_m);
  } else if (depth.type() == CV_32FC1) {
    depth.copyTo(out);
    out.forEach<float>([](float& z, const int*) {
      if (!std::isfinite(z) || z <= 0) z = 0;
    });
  } else {
    throw Error("depth must be single-channel uint16 or float32");
  }
  return out;
}

cv::Mat median_depth(const cv::Mat& depth) {
  // OpenCV's median (SIMD) for the bulk; pixels next to a hole are redone over valid neighbours only,
  // so that missing data neither spreads nor drags a surface towards zero.
  cv::Mat out;
  cv::medianBlur(depth, out, 3);
  // Pixels within one pixel of a hole (found with an erosion of the valid mask) are redone over their
  // valid neighbours only; OpenCV's median replicates the border, so border pixels are redone too.
  cv::Mat valid = depth > 0, redo;
  cv::erode(valid, redo, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  redo = valid & ~redo;
  const int rows = depth.rows, cols = depth.cols;
  parallel_for_rows(rows, [&](int begin, int end) {
    float v[9];
    for (int y = begin; y < end; ++y) {
      float* o = out.ptr<float>(y);
      const uchar* r = redo.ptr<uchar>(y);
      const uchar* ok = valid.ptr<uchar>(y);
      for (int x = 0; x < cols; ++x) {
        if (!ok[x]) { o[x] = 0; continue; }
        if (!r[x]) continue;
        int n = 0;
        for (int yy = std::max(y - 1, 0); yy <= std::min(y + 1, rows - 1); ++yy)
          for (int xx = std::max(x - 1, 0); xx <= std::min(x + 1, cols - 1); ++xx) {
            const float z = depth.ptr<float>(yy)[xx];
            if (z > 0) v[n++] = z;
          }
        std::nth_element(v, v + n / 2, v + n);
        o[x] = v[n / 2];
      }
    }
  });
  return out;
}

cv::Mat TemporalSmoother::push(const cv::Mat& depth, const Params::Smoothing& params) {
  if (!window_.empty() && window_.back().size() != depth.size()) window_.clear();
  window_.push_back(depth.clone());
  while (static_cast<int>(window_.size()) > std::max(1, params.temporal_frames)) window_.pop_front();
  if (window_.size() == 1) return depth.clone();

  cv::Mat out(depth.size(), CV_32F);
  const int n = static_cast<int>(window_.size());
  std::vector<const cv::Mat*> frames;
  for (const auto& f : window_) frames.push_back(&f);
  const float band_k = static_cast<float>(params.temporal_band);
  parallel_for_rows(depth.rows, [&](int begin, int end) {
    std::vector<float> count(static_cast<size_t>(depth.cols));
    for (int y = begin; y < end; ++y) {
      const float* newest = frames.back()->ptr<float>(y);
      float* sum = out.ptr<float>(y);
      std::fill(sum, sum + depth.cols, 0.f);
      std::fill(count.begin(), count.end(), 0.f);
      // Frame by frame over whole rows, branch-free, so that it vectorises.
      for (int i = 0; i < n; ++i) {
        const float* v = frames[static_cast<size_t>(i)]->ptr<float>(y);
        for (int x = 0; x < depth.cols; ++x) {
          const float z = newest[x];
          const bool take = (v[x] > 0) & (std::abs(v[x] - z) <= band_k * z * z);
          sum[x] += take ? v[x] : 0.f;
          count[static_cast<size_t>(x)] += take ? 1.f : 0.f;
        }
      }
      // The newest value is within its own band, so count >= 1 wherever it is valid.
      for (int x = 0; x < depth.cols; ++x) sum[x] = newest[x] > 0 ? sum[x] / count[static_cast<size_t>(x)] : 0.f;
    }
  });
  return out;
}

}  // namespace clutterseg
