#include "clutterseg/edges.hpp"

#include <cmath>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

constexpr int kDirs[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};

// v[x] += |n(x) . q(x)| over x in [0, count): one neighbour direction of a row.
CLUTTERSEG_ROW_KERNEL void add_abs_dot(const float* __restrict nx, const float* __restrict ny,
                                       const float* __restrict nz, const float* __restrict qx,
                                       const float* __restrict qy, const float* __restrict qz, int count,
                                       float* __restrict v) {
  for (int x = 0; x < count; ++x) v[x] += std::abs(nx[x] * qx[x] + ny[x] * qy[x] + nz[x] * qz[x]);
}

// big[x] = max(big[x], |q[x] - z[x]|) where q[x] is a measurement.
CLUTTERSEG_ROW_KERNEL void max_jump(const float* __restrict z, const float* __restrict q, int count,
                                    float* __restrict big) {
  for (int x = 0; x < count; ++x) big[x] = std::max(big[x], q[x] > 0 ? std::abs(q[x] - z[x]) : 0.f);
}

CLUTTERSEG_ROW_KERNEL void binarize(const float* __restrict z, const float* __restrict v,
                                    const float* __restrict big, int cols, float theta, float jump_limit,
                                    uchar* __restrict e) {
  for (int x = 0; x < cols; ++x)
    e[x] = static_cast<uchar>(((z[x] <= 0) | (v[x] < theta) | (big[x] > jump_limit * z[x])) * 255);
}

}  // namespace

cv::Mat normal_edge_value(const cv::Mat& normals, int step) {
  const int rows = normals.rows, cols = normals.cols;
  // Planar copies make the inner loops plain float arrays. A missing normal is (0,0,0), so it
  // contributes 0 to its neighbours' mean and gets 0 itself, without a branch.
  cv::Mat n[3];
  cv::split(normals, n);
  cv::Mat value(normals.size(), CV_32F, cv::Scalar(0));
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      float* v = value.ptr<float>(y);
      const bool inner_row = y >= step && y + step < rows;
      const int x0 = inner_row ? step : cols, x1 = inner_row ? cols - step : cols;
      if (inner_row) {
        for (const auto& d : kDirs) {
          const int yy = y + d[1] * step, dx = d[0] * step;
          add_abs_dot(n[0].ptr<float>(y) + x0, n[1].ptr<float>(y) + x0, n[2].ptr<float>(y) + x0,
                      n[0].ptr<float>(yy) + x0 + dx, n[1].ptr<float>(yy) + x0 + dx, n[2].ptr<float>(yy) + x0 + dx,
                      x1 - x0, v + x0);
        }
        for (int x = x0; x < x1; ++x) v[x] *= 0.125f;
      }
      // Image border: the mean over the neighbours that lie inside the image.
      for (int x = 0; x < cols; ++x) {
        if (x == x0) x = x1;
        if (x >= cols) break;
        float sum = 0;
        int count = 0;
        for (const auto& d : kDirs) {
          const int xx = x + d[0] * step, yy = y + d[1] * step;
          if (xx < 0 || yy < 0 || xx >= cols || yy >= rows) continue;
          sum += std::abs(n[0].ptr<float>(y)[x] * n[0].ptr<float>(yy)[xx] + n[1].ptr<float>(y)[x] * n[1].ptr<float>(yy)[xx] +
                          n[2].ptr<float>(y)[x] * n[2].ptr<float>(yy)[xx]);
          ++count;
        }
        v[x] = sum / static_cast<float>(count);
      }
    }
  });
  return value;
}

cv::Mat edge_mask(const cv::Mat& edge_value, const cv::Mat& depth, double theta, float jump_limit) {
  const int rows = depth.rows, cols = depth.cols;
  cv::Mat edges(depth.size(), CV_8U);
  parallel_for_rows(rows, [&](int begin, int end) {
    std::vector<float> largest(static_cast<size_t>(cols));
    for (int y = begin; y < end; ++y) {
      const float* z = depth.ptr<float>(y);
      // Largest depth difference to a valid adjacent pixel (8 directions; outside the image skipped).
      std::fill(largest.begin(), largest.end(), 0.f);
      for (int dy = -1; dy <= 1; ++dy) {
        if (y + dy < 0 || y + dy >= rows) continue;
        const float* q = depth.ptr<float>(y + dy);
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int xb = std::max(0, -dx), xe = cols - std::max(0, dx);
          max_jump(z + xb, q + xb + dx, xe - xb, largest.data() + xb);
        }
      }
      binarize(z, edge_value.ptr<float>(y), largest.data(), cols, static_cast<float>(theta), jump_limit, edges.ptr<uchar>(y));
    }
  });
  return edges;
}

}  // namespace clutterseg
