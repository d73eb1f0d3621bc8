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
  const int rows = depth.rows, cols = depth.cols;
  parallel_for_rows(rows, [&](int begin, int end) {
    float v[9];
    for (int y = begin; y < end; ++y) {
      float* o = out.ptr<float>(y);
      const float* c = depth.ptr<float>(y);
      for (int x = 0; x < cols; ++x) {
        if (c[x] <= 0) { o[x] = 0; continue; }
        bool hole = y == 0 || x == 0 || y == rows - 1 || x == cols - 1;
        for (int dy = -1; dy <= 1 && !hole; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            if (depth.at<float>(y + dy, x + dx) <= 0) { hole = true; break; }
        if (!hole) continue;
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int yy = y + dy, xx = x + dx;
            if (yy < 0 || xx < 0 || yy >= rows || xx >= cols) continue;
            const float z = depth.at<float>(yy, xx);
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
  parallel_for_rows(depth.rows, [&](int begin, int end) {
    std::vector<const float*> row(n);
    for (int y = begin; y < end; ++y) {
      for (int i = 0; i < n; ++i) row[i] = frames[i]->ptr<float>(y);
      const float* newest = row[n - 1];
      float* o = out.ptr<float>(y);
      for (int x = 0; x < depth.cols; ++x) {
        const float z = newest[x];
        if (z <= 0) { o[x] = 0; continue; }
        const float band = static_cast<float>(params.temporal_band) * z * z;
        float sum = 0;
        int count = 0;
        for (int i = 0; i < n; ++i) {
          const float v = row[i][x];
          if (v > 0 && std::abs(v - z) <= band) { sum += v; ++count; }
        }
        o[x] = sum / count;  // count >= 1: the newest value is always within its own band
      }
    }
  });
  return out;
}

}  // namespace clutterseg
