#include "clutterseg/edges.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

constexpr int kDirs[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};

// One row of the edge value away from the left and right image border, columns [x0, x1): `scale`
// times the sum over the 8 neighbours `s` pixels away of |n . n_q| (scale 1/8: their mean). Normals
// come as planes (x, y, z) of the rows y - s, y, y + s.
CLUTTERSEG_ROW_KERNEL void edge_value_row(const float* __restrict ux, const float* __restrict uy,
                                          const float* __restrict uz, const float* __restrict mx,
                                          const float* __restrict my, const float* __restrict mz,
                                          const float* __restrict dx, const float* __restrict dy,
                                          const float* __restrict dz, int s, int x0, int x1, float scale,
                                          float* __restrict v) {
  for (int x = x0; x < x1; ++x) {
    const float a = mx[x], b = my[x], c = mz[x];
    auto cosine = [&](const float* qx, const float* qy, const float* qz, int q) {
      return std::abs(a * qx[q] + b * qy[q] + c * qz[q]);
    };
    // In the order of kDirs (the border code below), so both give the same bits.
    float sum = 0;
    sum += cosine(ux, uy, uz, x - s);
    sum += cosine(ux, uy, uz, x);
    sum += cosine(ux, uy, uz, x + s);
    sum += cosine(mx, my, mz, x - s);
    sum += cosine(mx, my, mz, x + s);
    sum += cosine(dx, dy, dz, x - s);
    sum += cosine(dx, dy, dz, x);
    sum += cosine(dx, dy, dz, x + s);
    v[x] = sum * scale;
  }
}

// |q - z| where q is a measurement, else 0.
inline float jump(float q, float z) { return q > 0 ? std::abs(q - z) : 0.f; }

// One row of the edge mask: an edge where there is no measurement, where the
// normal-edge value is below theta, or where a depth jump to one of the 8 adjacent pixels is larger
// than jump_limit * z. Rows `up` and `down` are the rows above and below (the row itself at the image
// border, which makes no jump).
CLUTTERSEG_ROW_KERNEL void edge_row(const float* __restrict up, const float* __restrict z,
                                    const float* __restrict down, const float* __restrict value, int cols,
                                    float theta, float jump_limit, uchar* __restrict e) {
  for (int x = 0; x < cols; ++x) {
    const float c = z[x];
    const float largest = std::max({jump(up[x - 1], c), jump(up[x], c), jump(up[x + 1], c), jump(z[x - 1], c),
                                    jump(z[x + 1], c), jump(down[x - 1], c), jump(down[x], c), jump(down[x + 1], c)});
    e[x] = static_cast<uchar>(((c <= 0) | (value[x] < theta) | (largest > jump_limit * c)) * 255);
  }
}

}  // namespace

cv::Mat normal_edge_value(const cv::Mat& normals, int step) {
  NormalPlanes planes;
  cv::split(normals, planes.data());
  return normal_edge_value(planes, step);
}

cv::Mat normal_edge_value(const NormalPlanes& n, int step) {
  // Planes make the inner loops plain float arrays. A missing normal is (0,0,0), so it contributes 0
  // to its neighbours' mean and gets 0 itself, without a branch.
  const int rows = n[0].rows, cols = n[0].cols;
  cv::Mat value(n[0].size(), CV_32F);
  const std::vector<float> zeros(static_cast<size_t>(cols), 0.f);  // a row outside the image: no normals
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      float* v = value.ptr<float>(y);
      // row[r][c]: plane c of the image row (r - 1) * step away, zeros outside the image.
      const float* row[3][3];
      int inside = 8;  // neighbours inside the image, away from the left and right border
      for (int r = 0; r < 3; ++r) {
        const int yy = y + (r - 1) * step;
        const bool in_image = yy >= 0 && yy < rows;
        inside -= in_image ? 0 : 3;
        for (int c = 0; c < 3; ++c) row[r][c] = in_image ? n[c].ptr<float>(yy) : zeros.data();
      }
      // Away from the left and right border: a row outside adds zeros, so the sum is that over the
      // neighbours inside, in the same order; the mean divides by their number.
      const int x0 = std::min(step, cols), x1 = std::max(cols - step, x0);
      edge_value_row(row[0][0], row[0][1], row[0][2], row[1][0], row[1][1], row[1][2], row[2][0], row[2][1],
                     row[2][2], step, x0, x1, inside == 8 ? 0.125f : 1.f, v);
      if (inside < 8)
        for (int x = x0; x < x1; ++x) v[x] /= static_cast<float>(inside);
      // The left and right border: the mean over the neighbours that lie inside the image.
      for (int x = 0; x < cols; ++x) {
        if (x == x0) x = x1;
        if (x >= cols) break;
        float sum = 0;
        int count = 0;
        const float a = row[1][0][x], b = row[1][1][x], c = row[1][2][x];
        for (const auto& d : kDirs) {
          const float* const* q = row[d[1] + 1];
          const int xx = x + d[0] * step, yy = y + d[1] * step;
          if (xx < 0 || xx >= cols || yy < 0 || yy >= rows) continue;
          sum += std::abs(a * q[0][xx] + b * q[1][xx] + c * q[2][xx]);
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
  // Rows with one replicated column on either side (a pixel outside the image makes no jump), each
  // copied once into a ring of three small buffers rather than a padded copy of the whole image.
  parallel_for_rows(rows, [&](int begin, int end) {
    const size_t stride = static_cast<size_t>(cols) + 2;
    std::vector<float> ring(3 * stride);
    int held[3] = {-1, -1, -1};  // the image row in each buffer
    const auto padded = [&](int y) {
      const int slot = y % 3;
      float* row = ring.data() + static_cast<size_t>(slot) * stride + 1;
      if (held[slot] != y) {
        const float* from = depth.ptr<float>(y);
        std::copy_n(from, cols, row);
        row[-1] = from[0];
        row[cols] = from[cols - 1];
        held[slot] = y;
      }
      return row;
    };
    for (int y = begin; y < end; ++y) {
      // The row itself stands in above the first row and below the last one.
      const float* up = padded(std::max(y - 1, 0));
      const float* z = padded(y);
      const float* down = padded(std::min(y + 1, rows - 1));
      edge_row(up, z, down, edge_value.ptr<float>(y), cols, static_cast<float>(theta), jump_limit, edges.ptr<uchar>(y));
    }
  });
  return edges;
}

double median_edge_value(const cv::Mat& edge_value, const cv::Mat& depth, int stride) {
  CV_Assert(edge_value.type() == CV_32F && depth.type() == CV_32F && edge_value.size() == depth.size() && stride > 0);
  std::vector<float> sample;
  sample.reserve(static_cast<size_t>((edge_value.rows / stride + 1) * (edge_value.cols / stride + 1)));
  for (int y = 0; y < edge_value.rows; y += stride) {
    const float* v = edge_value.ptr<float>(y);
    const float* z = depth.ptr<float>(y);
    for (int x = 0; x < edge_value.cols; x += stride)
      if (valid_depth(z[x])) sample.push_back(v[x]);
  }
  if (sample.empty()) return 1;
  const auto middle = sample.begin() + static_cast<std::ptrdiff_t>(sample.size() / 2);
  std::nth_element(sample.begin(), middle, sample.end());
  return *middle;
}

}  // namespace clutterseg
