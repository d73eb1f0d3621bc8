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

namespace {

// sum += v and count += 1 where v is a measurement within band_k * z^2 of the centre z.
CLUTTERSEG_ROW_KERNEL void accumulate_within_band(const float* __restrict v, const float* __restrict centre, int cols,
                                                  float band_k, float* __restrict sum, float* __restrict count) {
  for (int x = 0; x < cols; ++x) {
    const float z = centre[x];
    const bool take = (v[x] > 0) & (std::abs(v[x] - z) <= band_k * z * z);
    sum[x] += take ? v[x] : 0.f;
    count[x] += take ? 1.f : 0.f;
  }
}

}  // namespace

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
    const size_t cols = static_cast<size_t>(depth.cols);
    std::vector<float> sum(cols), count(cols), centre(cols);
    for (int y = begin; y < end; ++y) {
      const float* newest = frames.back()->ptr<float>(y);
      float* o = out.ptr<float>(y);
      // Two passes: the band around the newest value finds the values of the same surface (moving
      // surfaces keep only the newest), then the band around their mean, a steadier centre than one
      // noisy sample, takes the whole static run, so the noise falls by about sqrt(n).
      for (int pass = 0; pass < 2; ++pass) {
        const float* around = pass == 0 ? newest : centre.data();
        std::fill(sum.begin(), sum.end(), 0.f);
        std::fill(count.begin(), count.end(), 0.f);
        for (int i = 0; i < n; ++i)
          accumulate_within_band(frames[static_cast<size_t>(i)]->ptr<float>(y), around, depth.cols, band_k, sum.data(),
                                 count.data());
        float* mean = pass == 0 ? centre.data() : o;
        for (size_t x = 0; x < cols; ++x) mean[x] = newest[x] > 0 ? sum[x] / std::max(count[x], 1.f) : 0.f;
      }
    }
  });
  return out;
}

}  // namespace clutterseg
