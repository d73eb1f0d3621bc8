#include "clutterseg/edges.hpp"

#include <cmath>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {
constexpr int kDirs[8][2] = {{-1, -1}, {0, -1}, {1, -1}, {-1, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}};
}

cv::Mat normal_edge_value(const cv::Mat& normals, int step) {
  const int rows = normals.rows, cols = normals.cols;
  cv::Mat value(normals.size(), CV_32F, cv::Scalar(0));
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const auto* n = normals.ptr<cv::Vec3f>(y);
      float* v = value.ptr<float>(y);
      for (int x = 0; x < cols; ++x) {
        if (n[x][2] == 0) continue;
        float sum = 0;
        int count = 0;
        for (const auto& d : kDirs) {
          const int xx = x + d[0] * step, yy = y + d[1] * step;
          if (xx < 0 || yy < 0 || xx >= cols || yy >= rows) continue;
          sum += std::abs(n[x].dot(normals.at<cv::Vec3f>(yy, xx)));
          ++count;
        }
        v[x] = count ? sum / count : 0;
      }
    }
  });
  return value;
}

cv::Mat edge_mask(const cv::Mat& edge_value, const cv::Mat& points, double theta, float jump_limit) {
  const int rows = points.rows, cols = points.cols;
  cv::Mat edges(points.size(), CV_8U);
  const float th = static_cast<float>(theta);
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const float* v = edge_value.ptr<float>(y);
      const auto* p = points.ptr<cv::Vec3f>(y);
      uchar* e = edges.ptr<uchar>(y);
      for (int x = 0; x < cols; ++x) {
        const float z = p[x][2];
        bool edge = z <= 0 || v[x] < th;
        for (int k = 0; k < 8 && !edge; ++k) {
          const int xx = x + kDirs[k][0], yy = y + kDirs[k][1];
          if (xx < 0 || yy < 0 || xx >= cols || yy >= rows) continue;
          const float zq = points.at<cv::Vec3f>(yy, xx)[2];
          edge = zq > 0 && std::abs(zq - z) > jump_limit * z;
        }
        e[x] = edge ? 255 : 0;
      }
    }
  });
  return edges;
}

}  // namespace clutterseg
