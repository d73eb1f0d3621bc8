#include "clutterseg/edges.hpp"

#include <cmath>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {
constexpr int kDirs[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};
}

cv::Mat normal_edge_value(const cv::Mat& normals, int step) {
  const int rows = normals.rows, cols = normals.cols;
  // Planar copies make the inner loops plain float arrays the compiler vectorises. A missing normal is
  // (0,0,0), so it contributes 0 to its neighbours' mean and gets 0 itself, without a branch.
  cv::Mat n[3];
  cv::split(normals, n);
  cv::Mat value(normals.size(), CV_32F, cv::Scalar(0));
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const float* nx = n[0].ptr<float>(y);
      const float* ny = n[1].ptr<float>(y);
      const float* nz = n[2].ptr<float>(y);
      float* v = value.ptr<float>(y);
      const bool inner_row = y >= step && y + step < rows;
      const int x0 = inner_row ? step : cols, x1 = inner_row ? cols - step : cols;
      if (inner_row) {
        for (const auto& d : kDirs) {
          const int dy = d[1] * step, dx = d[0] * step;
          const float* qx = n[0].ptr<float>(y + dy) + dx;
          const float* qy = n[1].ptr<float>(y + dy) + dx;
          const float* qz = n[2].ptr<float>(y + dy) + dx;
          for (int x = x0; x < x1; ++x) v[x] += std::abs(nx[x] * qx[x] + ny[x] * qy[x] + nz[x] * qz[x]);
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
          sum += std::abs(nx[x] * n[0].ptr<float>(yy)[xx] + ny[x] * n[1].ptr<float>(yy)[xx] + nz[x] * n[2].ptr<float>(yy)[xx]);
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
  const float th = static_cast<float>(theta);
  parallel_for_rows(rows, [&](int begin, int end) {
    std::vector<float> largest(static_cast<size_t>(cols));
    for (int y = begin; y < end; ++y) {
      const float* v = edge_value.ptr<float>(y);
      const float* z = depth.ptr<float>(y);
      uchar* e = edges.ptr<uchar>(y);
      // Largest depth difference to a valid adjacent pixel (8 directions; outside the image skipped).
      float* big = largest.data();
      std::fill(largest.begin(), largest.end(), 0.f);
      for (int dy = -1; dy <= 1; ++dy) {
        if (y + dy < 0 || y + dy >= rows) continue;
        const float* q = depth.ptr<float>(y + dy);
        for (int dx = -1; dx <= 1; ++dx) {
          if (dx == 0 && dy == 0) continue;
          const int xb = std::max(0, -dx), xe = cols - std::max(0, dx);
          for (int x = xb; x < xe; ++x) {
            const float zq = q[x + dx];
            big[x] = std::max(big[x], zq > 0 ? std::abs(zq - z[x]) : 0.f);
          }
        }
      }
      for (int x = 0; x < cols; ++x)
        e[x] = static_cast<uchar>(((z[x] <= 0) | (v[x] < th) | (big[x] > jump_limit * z[x])) * 255);
    }
  });
  return edges;
}

}  // namespace clutterseg
