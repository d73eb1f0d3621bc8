#include "clutterseg/smoothing.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
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
    // A plain loop (Mat::forEach computes each pixel's position: ~5x slower); the Pipeline's workers
    // pass every smoothed frame through here again.
    for (int y = 0; y < depth.rows; ++y) {
      const float* in = depth.ptr<float>(y);
      float* o = out.ptr<float>(y);
      for (int x = 0; x < depth.cols; ++x) o[x] = std::isfinite(in[x]) && in[x] > 0 ? in[x] : 0.f;
    }
  } else {
    throw Error("depth must be single-channel uint16 or float32");
  }
  return out;
}

namespace {

// Floyd's sorting network for nine values (25 compare-exchanges), on floats or on 8 lanes of floats
// (the compare-exchange is std::min and std::max, written so that it also applies lane by lane).
using Float8 = float __attribute__((vector_size(32)));
using Int8 = int __attribute__((vector_size(32)));
template <typename V>
inline void sort_nine(V (&v)[9]) {
  static constexpr int kNetwork[25][2] = {{0, 1}, {3, 4}, {6, 7}, {1, 2}, {4, 5}, {7, 8}, {0, 1}, {3, 4}, {6, 7},
                                          {0, 3}, {3, 6}, {0, 3}, {1, 4}, {4, 7}, {1, 4}, {2, 5}, {5, 8}, {2, 5},
                                          {1, 3}, {5, 7}, {2, 6}, {4, 6}, {2, 4}, {2, 3}, {5, 6}};
#pragma GCC unroll 25  // unrolled, v stays in registers
  for (const auto& [a, b] : kNetwork) {
    const V lo = v[b] < v[a] ? v[b] : v[a], hi = v[a] < v[b] ? v[b] : v[a];
    v[a] = lo;
    v[b] = hi;
  }
}
constexpr float kMissing = std::numeric_limits<float>::infinity();

// Median of the valid (> 0) values among the 3x3 neighbours of (x, y), for a pixel next to a hole or
// the image border. The nine values are sorted, a missing one as +inf so that it sorts last; the
// median of the n valid values is then element n / 2. No branch depends on the data: around holes,
// which neighbours are valid is not predictable.
float median_of_valid_neighbours(const cv::Mat& depth, int x, int y) {
  float v[9];
  int n = 0;
  for (int dy = -1, k = 0; dy <= 1; ++dy) {
    const int yy = std::clamp(y + dy, 0, depth.rows - 1);
    for (int dx = -1; dx <= 1; ++dx, ++k) {
      const int xx = std::clamp(x + dx, 0, depth.cols - 1);
      const bool inside = yy == y + dy && xx == x + dx;
      const float z = depth.ptr<float>(yy)[xx];
      const bool valid = inside & (z > 0);
      v[k] = valid ? z : kMissing;
      n += valid;
    }
  }
  sort_nine(v);
  return v[n / 2];  // n >= 1: the pixel itself is valid
}

// median_of_valid_neighbours of the 8 pixels x .. x + 7 of row `mid`, in the lanes of 8-float vectors:
// the neighbours are 8 consecutive floats of each row. Away from the left and right image border
// (1 <= x, x + 9 <= cols); `up` and `down` are rows of zeros beyond the top and bottom. The same
// network on the same values: the same bits as one pixel at a time.
CLUTTERSEG_AVX2_KERNEL void medians_of_valid_neighbours(const float* __restrict up, const float* __restrict mid,
                                                        const float* __restrict down, int x, float* __restrict out) {
  const float* rows[3] = {up, mid, down};
  const Float8 zero = {}, missing = zero + kMissing;
  Float8 v[9];
  Int8 n = {};
  for (int dy = 0, k = 0; dy < 3; ++dy)
    for (int dx = -1; dx <= 1; ++dx, ++k) {
      Float8 z;
      std::memcpy(&z, rows[dy] + x + dx, sizeof z);
      const Int8 valid = z > zero;  // -1 in valid lanes
      v[k] = valid ? z : missing;
      n -= valid;
    }
  sort_nine(v);
  const Int8 half = n >> 1;
  Float8 median = v[0];
  for (int k = 1; k < 9; ++k) median = half == k ? v[k] : median;
  std::memcpy(out, &median, sizeof median);
}

// One row of the median's fix-up, columns [1, cols - 1): out = 0 where mid has no measurement (OpenCV's
// median fills holes), and redo = 1 where mid has one but a 3x3 neighbour in up, mid or down has not.
CLUTTERSEG_AVX2_KERNEL void mark_hole_borders(const float* __restrict up, const float* __restrict mid,
                                             const float* __restrict down, int cols, float* __restrict out,
                                             uchar* __restrict redo) {
  for (int x = 1; x + 1 < cols; ++x) {
    const bool valid = mid[x] > 0;
    const bool all_valid = (up[x - 1] > 0) & (up[x] > 0) & (up[x + 1] > 0) & (mid[x - 1] > 0) & (mid[x + 1] > 0) &
                           (down[x - 1] > 0) & (down[x] > 0) & (down[x + 1] > 0);
    out[x] = valid ? out[x] : 0.f;
    redo[x] = valid & !all_valid;
  }
}

}  // namespace

cv::Mat checked_metres(const cv::Mat& depth, const Camera& camera) {
  if (depth.empty()) throw Error("depth image is empty");
  check_camera(camera, depth.cols, depth.rows, "camera");
  cv::Mat metres = depth_to_metres(depth, camera);
  if (cv::countNonZero(metres) == 0) throw Error("depth image has no valid measurement");
  return metres;
}

cv::Mat median_depth(const cv::Mat& depth) {
  // OpenCV's median (SIMD) for the bulk. Pixels within one pixel of a hole or of the image border
  // (OpenCV replicates the border) are redone over their valid neighbours only, so that missing data
  // neither spreads nor drags a surface towards zero; holes stay holes.
  cv::Mat out;
  cv::medianBlur(depth, out, 3);
  const int cols = depth.cols;
  const std::vector<float> outside(static_cast<size_t>(cols), 0.f);  // the rows beyond the border: no data
  parallel_for_rows(depth.rows, [&](int begin, int end) {
    std::vector<uchar> redo(static_cast<size_t>(cols));
    for (int y = begin; y < end; ++y) {
      const float* mid = depth.ptr<float>(y);
      const float* up = y > 0 ? depth.ptr<float>(y - 1) : outside.data();
      const float* down = y + 1 < depth.rows ? depth.ptr<float>(y + 1) : outside.data();
      float* o = out.ptr<float>(y);
      mark_hole_borders(up, mid, down, cols, o, redo.data());
      for (const int x : {0, cols - 1}) {  // the first and last column: next to the border
        const bool valid = mid[x] > 0;
        redo[static_cast<size_t>(x)] = valid;
        o[x] = valid ? o[x] : 0.f;
      }
      // Eight pixels at a time from the first one to redo (the pixels to redo come in clusters
      // around holes), one at a time at the left and right border.
      const uchar* r = redo.data();
      for (int x = first_nonzero(r, 0, cols); x < cols;) {
        if (x >= 1 && x + 9 <= cols) {
          float medians[8];
          medians_of_valid_neighbours(up, mid, down, x, medians);
          for (int k = 0; k < 8; ++k) o[x + k] = r[x + k] ? medians[k] : o[x + k];
          x = first_nonzero(r, x + 8, cols);
        } else {
          o[x] = median_of_valid_neighbours(depth, x, y);
          x = first_nonzero(r, x + 1, cols);
        }
      }
    }
  });
  return out;
}

namespace {

// s += v and c += 1 for each of the N values v (oldest first) that is a measurement in [lo, hi].
template <int N>
inline void add_within_band(const float* const* frame, int x, float lo, float hi, float& s, float& c) {
  for (int i = 0; i < N; ++i) {
    const float v = frame[i][x];
    const bool take = (v >= lo) & (v <= hi);
    s += take ? v : 0.f;
    c += take ? 1.f : 0.f;
  }
}

// The band [lo, hi] = centre +- band_k * centre^2; lo > 0, so that no missing measurement (0) falls in it.
inline void band(float z, float band_k, float& lo, float& hi) {
  const float limit = band_k * z * z;
  lo = std::max(z - limit, std::numeric_limits<float>::denorm_min());
  hi = z + limit;
}

// mean = the mean of the N frames' values (rows `v`, oldest first) within the band around the
// centre, where the newest frame has a measurement, else 0: one pass, sums in registers.
template <int N>
CLUTTERSEG_ROW_KERNEL void mean_within_band(const float* const* v, const float* __restrict centre,
                                            const float* __restrict newest, int cols, float band_k,
                                            float* __restrict mean) {
  const float* frame[N];
  for (int i = 0; i < N; ++i) frame[i] = v[i];
  for (int x = 0; x < cols; ++x) {
    float lo, hi, s = 0, c = 0;
    band(centre[x], band_k, lo, hi);
    add_within_band<N>(frame, x, lo, hi, s, c);
    mean[x] = newest[x] > 0 ? s / std::max(c, 1.f) : 0.f;
  }
}

// The same as sums and counts, for windows longer than one kernel takes: sum += v and count += 1 over
// N frames. The frames are added in the same order, so the bits do not depend on how the window is
// cut into chunks.
template <int N>
CLUTTERSEG_ROW_KERNEL void accumulate_within_band(const float* const* v, const float* __restrict centre, int cols,
                                                  float band_k, float* __restrict sum, float* __restrict count) {
  const float* frame[N];
  for (int i = 0; i < N; ++i) frame[i] = v[i];
  for (int x = 0; x < cols; ++x) {
    float lo, hi, s = sum[x], c = count[x];
    band(centre[x], band_k, lo, hi);
    add_within_band<N>(frame, x, lo, hi, s, c);
    sum[x] = s;
    count[x] = c;
  }
}

// One kernel per frame count, up to kChunk frames.
constexpr int kChunk = 8;
using MeanKernel = void (*)(const float* const*, const float*, const float*, int, float, float*);
using AccumulateKernel = void (*)(const float* const*, const float*, int, float, float*, float*);
template <size_t... I>
constexpr std::array<MeanKernel, sizeof...(I)> mean_kernels(std::index_sequence<I...>) {
  return {&mean_within_band<static_cast<int>(I) + 1>...};
}
template <size_t... I>
constexpr std::array<AccumulateKernel, sizeof...(I)> accumulate_kernels(std::index_sequence<I...>) {
  return {&accumulate_within_band<static_cast<int>(I) + 1>...};
}

// mean = the mean of the rows' values within the band around the centre, where `newest` has a
// measurement. Windows of up to kChunk frames in one pass; longer ones kChunk frames at a time into
// sum and count (scratch rows).
void mean_within_band(const std::vector<const float*>& rows, const float* centre, const float* newest, int cols,
                      float band_k, float* sum, float* count, float* mean) {
  static constexpr auto kMeans = mean_kernels(std::make_index_sequence<kChunk>{});
  static constexpr auto kAccumulates = accumulate_kernels(std::make_index_sequence<kChunk>{});
  if (rows.size() <= kChunk) {
    kMeans[rows.size() - 1](rows.data(), centre, newest, cols, band_k, mean);
    return;
  }
  std::fill(sum, sum + cols, 0.f);
  std::fill(count, count + cols, 0.f);
  for (size_t first = 0; first < rows.size(); first += kChunk) {
    const size_t n = std::min<size_t>(kChunk, rows.size() - first);
    kAccumulates[n - 1](rows.data() + first, centre, cols, band_k, sum, count);
  }
  for (int x = 0; x < cols; ++x) mean[x] = newest[x] > 0 ? sum[x] / std::max(count[x], 1.f) : 0.f;
}

}  // namespace

bool scene_changed(const cv::Mat& previous, const cv::Mat& next, const Params::Smoothing& params) {
  if (previous.size() != next.size()) return true;
  // A sample of the pixels (every 4th of every 4th row of a frame that has enough) is plenty for a share.
  const int stride = next.total() >= 64 * 64 ? 4 : 1;
  int both = 0, moved = 0;
  const auto k = static_cast<float>(params.temporal_band);
  for (int y = 0; y < next.rows; y += stride) {
    const float* a = previous.ptr<float>(y);
    const float* b = next.ptr<float>(y);
    for (int x = 0; x < next.cols; x += stride) {
      if (!valid_depth(a[x]) || !valid_depth(b[x])) continue;
      ++both;
      moved += std::abs(b[x] - a[x]) > k * b[x] * b[x];
    }
  }
  // Pixels measured in one frame only are never averaged anyway: without common pixels, nothing to decide.
  return both > 0 && moved > params.scene_change_share * both;
}

cv::Mat TemporalSmoother::make_room(const cv::Mat& next, const Params::Smoothing& params) {
  restarted_ = window_.empty() || scene_changed(window_.back(), next, params);
  if (restarted_) window_.clear();
  cv::Mat slot;
  while (static_cast<int>(window_.size()) >= std::max(1, params.temporal_frames)) {
    slot = std::move(window_.front());
    window_.pop_front();
  }
  return slot;
}

cv::Mat TemporalSmoother::push(const cv::Mat& depth, const Params::Smoothing& params) {
  cv::Mat slot = make_room(depth, params);  // the leaving frame's buffer takes the new one (no allocation)
  depth.copyTo(slot);
  window_.push_back(slot);
  return smooth_newest(params);
}

cv::Mat TemporalSmoother::push(cv::Mat&& depth, const Params::Smoothing& params) {
  make_room(depth, params);
  window_.push_back(std::move(depth));
  return smooth_newest(params);
}

cv::Mat TemporalSmoother::smooth_newest(const Params::Smoothing& params) const {
  const cv::Mat& depth = window_.back();
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
      mean_within_band(rows, newest, newest, depth.cols, band_k, sum.data(), count.data(), centre.data());
      mean_within_band(rows, centre.data(), newest, depth.cols, band_k, sum.data(), count.data(), o);
    }
  });
  return out;
}

}  // namespace clutterseg
