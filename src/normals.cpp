#include "clutterseg/normals.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

// One row of back-projected points: (x, y, z) = z * ((u - cx) / fx, (v - cy) / fy, 1), 0 where z = 0.
CLUTTERSEG_ROW_KERNEL void point_row(const float* __restrict z, const float* __restrict ray_x, float ray_y, int cols,
                                     float* __restrict p) {
  for (int x = 0; x < cols; ++x) {
    p[3 * x] = ray_x[x] * z[x];
    p[3 * x + 1] = ray_y * z[x];
    p[3 * x + 2] = z[x];
  }
}

// One row of raw normals. Plain pointers and values (no captures) so that the loop vectorises.
CLUTTERSEG_ROW_KERNEL void raw_normal_row(const float* __restrict up, const float* __restrict mid, const float* __restrict down,
                    const float* __restrict rx, float ry, float ry_up, float ry_down, int cols, int s,
                    float jump_limit, float* __restrict nx, float* __restrict ny, float* __restrict nz) {
  for (int x = 0; x < cols; ++x) {
    const float z = mid[x], lim = jump_limit * z;
    const float zl = mid[x - s], zr = mid[x + s], zu = up[x], zd = down[x];
    // Whether the neighbour continues the surface (a measurement, no depth jump).
    const bool l = (zl > 0.f) & (std::abs(zl - z) <= lim), r = (zr > 0.f) & (std::abs(zr - z) <= lim);
    const bool u = (zu > 0.f) & (std::abs(zu - z) <= lim), d = (zd > 0.f) & (std::abs(zd - z) <= lim);
    const float px = rx[x] * z, py = ry * z;
    // Horizontal tangent a - b, vertical tangent c - e; a missing neighbour is replaced by the centre.
    const float ax = r ? rx[x + s] * zr : px, ay = r ? ry * zr : py, az = r ? zr : z;
    const float bx = l ? rx[x - s] * zl : px, by = l ? ry * zl : py, bz = l ? zl : z;
    const float cx = d ? rx[x] * zd : px, cy = d ? ry_down * zd : py, cz = d ? zd : z;
    const float ex = u ? rx[x] * zu : px, ey = u ? ry_up * zu : py, ez = u ? zu : z;
    const float tux = ax - bx, tuy = ay - by, tuz = az - bz;
    const float tvx = cx - ex, tvy = cy - ey, tvz = cz - ez;
    // tv x tu faces the camera for any surface seen from the front (x right, y down, z forward).
    const float n0 = tvy * tuz - tvz * tuy, n1 = tvz * tux - tvx * tuz, n2 = tvx * tuy - tvy * tux;
    const float len2 = n0 * n0 + n1 * n1 + n2 * n2;
    const float inv = ((z > 0) & (len2 > 0)) ? 1.f / std::sqrt(len2) : 0.f;
    nx[x] = n0 * inv;
    ny[x] = n1 * inv;
    nz[x] = n2 * inv;
  }
}

// One pass of the separable Gaussian over a row: out[x] = w[0] c[x] + sum_k w[k] (a_k[x] + b_k[x]) for
// k = 1 .. r, where c = taps[r], a_k = taps[r - k], b_k = taps[r + k]. Down a column these are the rows
// k above and below; along a row, the same row shifted by k. Unrolled for the radii met in practice, so
// that each pixel sums in a register (one load per tap, one store); any other radius adds tap pair by
// tap pair.
template <int R>
[[gnu::always_inline]] inline void unrolled_taps(const float* const* taps, const float* __restrict w, int cols,
                                                 float* __restrict out) {
  const float* __restrict centre = taps[R];
  const float* __restrict before[R + 1];
  const float* __restrict after[R + 1];
  for (int k = 1; k <= R; ++k) before[k] = taps[R - k], after[k] = taps[R + k];
  for (int x = 0; x < cols; ++x) {
    float sum = w[0] * centre[x];
    for (int k = 1; k <= R; ++k) sum += w[k] * (before[k][x] + after[k][x]);
    out[x] = sum;
  }
}

CLUTTERSEG_ROW_KERNEL void add_tap_pair(const float* __restrict a, const float* __restrict b, float w, int cols,
                                        float* __restrict out) {
  for (int x = 0; x < cols; ++x) out[x] += w * (a[x] + b[x]);
}

CLUTTERSEG_ROW_KERNEL void smooth_taps(const float* const* taps, const float* __restrict w, int r, int cols,
                                       float* __restrict out) {
  switch (r) {
    case 1: return unrolled_taps<1>(taps, w, cols, out);
    case 2: return unrolled_taps<2>(taps, w, cols, out);
    case 3: return unrolled_taps<3>(taps, w, cols, out);
    case 4: return unrolled_taps<4>(taps, w, cols, out);
    case 5: return unrolled_taps<5>(taps, w, cols, out);
    case 6: return unrolled_taps<6>(taps, w, cols, out);
    case 7: return unrolled_taps<7>(taps, w, cols, out);
    case 8: return unrolled_taps<8>(taps, w, cols, out);
    default:
      for (int x = 0; x < cols; ++x) out[x] = w[0] * taps[r][x];
      for (int k = 1; k <= r; ++k) add_tap_pair(taps[r - k], taps[r + k], w[k], cols, out);
  }
}

// A Gaussian of 2 r + 1 taps (weights w[0 .. r] from the centre out) over one CV_32F plane, in place,
// the outermost values repeated beyond the border (cv::BORDER_REPLICATE). Each input row is smoothed
// along the row into a ring of the last 2 r + 1 rows before the output row r above it is written.
// OpenCV's GaussianBlur does the same, but at more than 5 taps its float row filter is a generic one
// that takes twice the time of this whole function (docs/BENCHMARKS.md, "Fifth speed pass").
void smooth_plane(cv::Mat& plane, const std::vector<float>& w) {
  const int rows = plane.rows, cols = plane.cols, r = static_cast<int>(w.size()) - 1, taps = 2 * r + 1;
  cv::Mat ring(taps, cols, CV_32F);  // cv::Mat rows are 64-byte aligned
  std::vector<const float*> window(static_cast<size_t>(taps)), shifted(static_cast<size_t>(taps));  // the taps
  // The columns within r of the left and right border, with the index clamped; the same sums in the
  // same order as smooth_taps, which takes the columns in between straight from the plane.
  const auto border_columns = [&](const float* in, int from, int to, float* out) {
    for (int x = from; x < to; ++x) {
      float sum = w[0] * in[x];
      for (int k = 1; k <= r; ++k) sum += w[static_cast<size_t>(k)] * (in[std::max(x - k, 0)] + in[std::min(x + k, cols - 1)]);
      out[x] = sum;
    }
  };
  const int inner_begin = std::min(r, cols), inner_end = std::max(cols - r, inner_begin);
  for (int y = 0, next = 0; y < rows; ++y) {
    for (; next <= std::min(y + r, rows - 1); ++next) {
      const float* in = plane.ptr<float>(next);
      float* out = ring.ptr<float>(next % taps);
      border_columns(in, 0, inner_begin, out);
      if (inner_end > inner_begin) {  // then inner_begin = r, and in + r + k stays inside the row
        for (int k = -r; k <= r; ++k) shifted[static_cast<size_t>(k + r)] = in + inner_begin + k;
        smooth_taps(shifted.data(), w.data(), r, inner_end - inner_begin, out + inner_begin);
      }
      border_columns(in, inner_end, cols, out);
    }
    for (int k = -r; k <= r; ++k) window[static_cast<size_t>(k + r)] = ring.ptr<float>(std::clamp(y + k, 0, rows - 1) % taps);
    smooth_taps(window.data(), w.data(), r, cols, plane.ptr<float>(y));
  }
}

// Renormalises one row of smoothed normals in place; 0 where there is no measurement.
CLUTTERSEG_ROW_KERNEL void normalize_row(const float* __restrict z, int cols, float* __restrict nx,
                                         float* __restrict ny, float* __restrict nz) {
  for (int x = 0; x < cols; ++x) {
    const float len2 = nx[x] * nx[x] + ny[x] * ny[x] + nz[x] * nz[x];
    const float inv = ((z[x] > 0) & (len2 > 1e-12f)) ? 1.f / std::sqrt(len2) : 0.f;
    nx[x] *= inv;
    ny[x] *= inv;
    nz[x] *= inv;
  }
}

}  // namespace

std::vector<float> ray_x(const Camera& camera, int cols) {
  const float ifx = static_cast<float>(1.0 / camera.fx), cx = static_cast<float>(camera.cx);
  std::vector<float> rays(static_cast<size_t>(cols));
  for (int u = 0; u < cols; ++u) rays[static_cast<size_t>(u)] = (static_cast<float>(u) - cx) * ifx;
  return rays;
}

cv::Mat depth_to_points(const cv::Mat& depth, const Camera& camera) {
  cv::Mat points(depth.size(), CV_32FC3);
  const std::vector<float> rays = ray_x(camera, depth.cols);
  parallel_for_rows(depth.rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y)
      point_row(depth.ptr<float>(y), rays.data(), ray_y(camera, y), depth.cols, points.ptr<float>(y));
  });
  return points;
}

float relative_jump_limit(const Params::Edges& params, int step, const Camera& camera) {
  // Lateral distance of pixels `step` apart at depth z is z * step / f.
  return static_cast<float>(params.jump_slope * step / std::min(camera.fx, camera.fy));
}

NormalPlanes compute_normals(const cv::Mat& depth, const Camera& camera, int step, int ksize, float jump_limit) {
  const int rows = depth.rows, cols = depth.cols, s = step;
  // The rays of depth_to_points, padded by s columns on either side (read only for neighbours inside
  // the image: the ones outside are holes).
  std::vector<float> column_ray(static_cast<size_t>(cols + 2 * s), 0.f);
  const std::vector<float> rays = ray_x(camera, cols);
  std::copy(rays.begin(), rays.end(), column_ray.begin() + s);
  const auto row_ray = [&](int v) { return ray_y(camera, v); };
  // A neighbour outside the image is "no measurement", like a hole: rows outside read a row of zeros,
  // and each row is copied between s zeros on either side (a small buffer, not a padded image).
  const std::vector<float> zeros(static_cast<size_t>(cols), 0.f);

  NormalPlanes planes = {cv::Mat(depth.size(), CV_32F), cv::Mat(depth.size(), CV_32F), cv::Mat(depth.size(), CV_32F)};
  parallel_for_rows(rows, [&](int begin, int end) {
    std::vector<float> mid(static_cast<size_t>(cols + 2 * s), 0.f);
    for (int y = begin; y < end; ++y) {
      std::copy_n(depth.ptr<float>(y), cols, mid.begin() + s);
      const float* up = y - s >= 0 ? depth.ptr<float>(y - s) : zeros.data();
      const float* down = y + s < rows ? depth.ptr<float>(y + s) : zeros.data();
      raw_normal_row(up, mid.data() + s, down, column_ray.data() + s, row_ray(y), row_ray(y - s), row_ray(y + s), cols,
                     s, jump_limit, planes[0].ptr<float>(y), planes[1].ptr<float>(y), planes[2].ptr<float>(y));
    }
  });
  if (ksize > 1) {
    // OpenCV's Gaussian weights (its sigma for the size, as cv::GaussianBlur), from the centre out.
    const cv::Mat kernel = cv::getGaussianKernel(ksize, 0, CV_32F);
    std::vector<float> weights(static_cast<size_t>(ksize / 2 + 1));
    for (size_t k = 0; k < weights.size(); ++k) weights[k] = kernel.at<float>(ksize / 2 + static_cast<int>(k));
    parallel_for_rows(3, [&](int begin, int end) {  // the three planes, each one in place
      for (int c = begin; c < end; ++c) smooth_plane(planes[static_cast<size_t>(c)], weights);
    });
  }
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y)
      normalize_row(depth.ptr<float>(y), cols, planes[0].ptr<float>(y), planes[1].ptr<float>(y), planes[2].ptr<float>(y));
  });
  return planes;
}

}  // namespace clutterseg
