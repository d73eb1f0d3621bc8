#include "clutterseg/smoothing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

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

namespace {

// Median of the valid (> 0) values among the 3x3 neighbours of (x, y), for a pixel next to a hole or
// the image border (insertion sort of at most 9 values).
float median_of_valid_neighbours(const cv::Mat& depth, int x, int y) {
  float v[9];
  int n = 0;
  auto insert = [&](float z) {
    if (!(z > 0)) return;
    int k = n++;
    for (; k > 0 && v[k - 1] > z; --k) v[k] = v[k - 1];
    v[k] = z;
  };
  if (x > 0 && y > 0 && x + 1 < depth.cols && y + 1 < depth.rows) {  // the common case: no clipping
    for (int yy = y - 1; yy <= y + 1; ++yy) {
      const float* row = depth.ptr<float>(yy) + x;
      insert(row[-1]);
      insert(row[0]);
      insert(row[1]);
    }
  } else {
    for (int yy = std::max(y - 1, 0); yy <= std::min(y + 1, depth.rows - 1); ++yy)
      for (int xx = std::max(x - 1, 0); xx <= std::min(x + 1, depth.cols - 1); ++xx) insert(depth.ptr<float>(yy)[xx]);
  }
  return v[n / 2];  // n >= 1: the pixel itself is valid
}

// v = 0 where mask is 0.
CLUTTERSEG_ROW_KERNEL void keep_where(const uchar* __restrict mask, int cols, float* __restrict v) {
  for (int x = 0; x < cols; ++x) v[x] = mask[x] ? v[x] : 0.f;
}

}  // namespace

cv::Mat median_depth(const cv::Mat& depth) {
  // OpenCV's median (SIMD) for the bulk. Pixels within one pixel of a hole or of the image border
  // (OpenCV replicates the border) are redone over their valid neighbours only, so that missing data
  // neither spreads nor drags a surface towards zero; holes stay holes.
  cv::Mat out;
  cv::medianBlur(depth, out, 3);
  cv::Mat valid = depth > 0, redo;
  cv::erode(valid, redo, cv::Mat(), cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  redo = valid & ~redo;  // valid, but next to a hole or the border
  parallel_for_rows(depth.rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      float* o = out.ptr<float>(y);
      const uchar* r = redo.ptr<uchar>(y);
      keep_where(valid.ptr<uchar>(y), depth.cols, o);
      for (int x = first_nonzero(r, 0, depth.cols); x < depth.cols; x = first_nonzero(r, x + 1, depth.cols))
        o[x] = median_of_valid_neighbours(depth, x, y);
    }
  });
  return out;
}

namespace {

// sum += v and count += 1 over N frames (rows `v`, oldest first), where v is a measurement within
// band_k * z^2 of the centre z. The N frames are summed in registers in that order, so the bits do
// not depend on how the window is cut into chunks of N.
template <int N>
CLUTTERSEG_ROW_KERNEL void accumulate_within_band(const float* const* v, const float* __restrict centre, int cols,
                                                  float band_k, float* __restrict sum, float* __restrict count) {
  const float* frame[N];
  for (int i = 0; i < N; ++i) frame[i] = v[i];
  for (int x = 0; x < cols; ++x) {
    const float z = centre[x], limit = band_k * z * z;
    float s = sum[x], c = count[x];
    for (int i = 0; i < N; ++i) {
      const bool take = (frame[i][x] > 0) & (std::abs(frame[i][x] - z) <= limit);
      s += take ? frame[i][x] : 0.f;
      c += take ? 1.f : 0.f;
    }
    sum[x] = s;
    count[x] = c;
  }
}

// accumulate_within_band over any number of frames, up to kChunk per call (one kernel per count).
constexpr int kChunk = 8;
using AccumulateKernel = void (*)(const float* const*, const float*, int, float, float*, float*);
template <size_t... I>
constexpr std::array<AccumulateKernel, sizeof...(I)> accumulate_kernels(std::index_sequence<I...>) {
  return {&accumulate_within_band<static_cast<int>(I) + 1>...};
}
void accumulate_within_band(const std::vector<const float*>& rows, const float* centre, int cols, float band_k,
                            float* sum, float* count) {
  static constexpr auto kKernels = accumulate_kernels(std::make_index_sequence<kChunk>{});
  for (size_t first = 0; first < rows.size(); first += kChunk) {
    const size_t n = std::min<size_t>(kChunk, rows.size() - first);
    kKernels[n - 1](rows.data() + first, centre, cols, band_k, sum, count);
  }
}

// mean = sum / count where the newest frame has a measurement, else 0.
CLUTTERSEG_ROW_KERNEL void mean_where_measured(const float* __restrict newest, const float* __restrict sum,
                                               const float* __restrict count, int cols, float* __restrict mean) {
  for (int x = 0; x < cols; ++x) mean[x] = newest[x] > 0 ? sum[x] / std::max(count[x], 1.f) : 0.f;
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
    std::vector<const float*> rows(static_cast<size_t>(n));
    for (int y = begin; y < end; ++y) {
      const float* newest = frames.back()->ptr<float>(y);
      for (int i = 0; i < n; ++i) rows[static_cast<size_t>(i)] = frames[static_cast<size_t>(i)]->ptr<float>(y);
      float* o = out.ptr<float>(y);
      // Two passes: the band around the newest value finds the values of the same surface (moving
      // surfaces keep only the newest), then the band around their mean, a steadier centre than one
      // noisy sample, takes the whole static run, so the noise falls by about sqrt(n).
      for (int pass = 0; pass < 2; ++pass) {
        const float* around = pass == 0 ? newest : centre.data();
        std::fill(sum.begin(), sum.end(), 0.f);
        std::fill(count.begin(), count.end(), 0.f);
        accumulate_within_band(rows, around, depth.cols, band_k, sum.data(), count.data());
        mean_where_measured(newest, sum.data(), count.data(), depth.cols, pass == 0 ? centre.data() : o);
      }
    }
  });
  return out;
}

}  // namespace clutterseg
