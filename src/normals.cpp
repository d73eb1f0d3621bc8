#include "clutterseg/normals.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

cv::Mat depth_to_points(const cv::Mat& depth, const Camera& camera) {
  cv::Mat points(depth.size(), CV_32FC3);
  const float ifx = static_cast<float>(1.0 / camera.fx), ify = static_cast<float>(1.0 / camera.fy);
  const float cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  parallel_for_rows(depth.rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const float* z = depth.ptr<float>(y);
      auto* p = points.ptr<cv::Vec3f>(y);
      const float ry = (y - cy) * ify;
      for (int x = 0; x < depth.cols; ++x)
        p[x] = z[x] > 0 ? cv::Vec3f((x - cx) * ifx * z[x], ry * z[x], z[x]) : cv::Vec3f(0, 0, 0);
    }
  });
  return points;
}

float relative_jump_limit(const Params::Edges& params, int step, const Camera& camera) {
  // Lateral distance of pixels `step` apart at depth z is z * step / f.
  return static_cast<float>(params.jump_slope * step / std::min(camera.fx, camera.fy));
}

namespace {

// Difference across p along one axis: central if both neighbours continue the surface, else one-sided.
inline bool tangent(const cv::Vec3f& p, const cv::Vec3f* prev, const cv::Vec3f* next, float limit,
                    cv::Vec3f& t) {
  const float lim = limit * p[2];
  const bool has_prev = prev && (*prev)[2] > 0 && std::abs((*prev)[2] - p[2]) <= lim;
  const bool has_next = next && (*next)[2] > 0 && std::abs((*next)[2] - p[2]) <= lim;
  if (has_prev && has_next) t = *next - *prev;
  else if (has_next) t = *next - p;
  else if (has_prev) t = p - *prev;
  else return false;
  return true;
}

}  // namespace

cv::Mat compute_normals(const cv::Mat& points, int step, int ksize, float jump_limit) {
  const int rows = points.rows, cols = points.cols;
  cv::Mat raw(points.size(), CV_32FC3, cv::Scalar::all(0));
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const auto* row = points.ptr<cv::Vec3f>(y);
      const auto* up = y >= step ? points.ptr<cv::Vec3f>(y - step) : nullptr;
      const auto* down = y + step < rows ? points.ptr<cv::Vec3f>(y + step) : nullptr;
      auto* out = raw.ptr<cv::Vec3f>(y);
      for (int x = 0; x < cols; ++x) {
        const cv::Vec3f& p = row[x];
        if (p[2] <= 0) continue;
        cv::Vec3f tu, tv;
        if (!tangent(p, x >= step ? &row[x - step] : nullptr, x + step < cols ? &row[x + step] : nullptr,
                     jump_limit, tu) ||
            !tangent(p, up ? &up[x] : nullptr, down ? &down[x] : nullptr, jump_limit, tv))
          continue;
        cv::Vec3f n = tu.cross(tv);
        const float len = static_cast<float>(cv::norm(n));
        if (len <= 0) continue;
        n *= (n.dot(p) > 0 ? -1.f : 1.f) / len;  // face the camera
        out[x] = n;
      }
    }
  });
  cv::Mat smooth;
  if (ksize > 1) cv::GaussianBlur(raw, smooth, cv::Size(ksize, ksize), 0, 0, cv::BORDER_REPLICATE);
  else smooth = raw;
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      auto* n = smooth.ptr<cv::Vec3f>(y);
      const auto* r = raw.ptr<cv::Vec3f>(y);
      for (int x = 0; x < cols; ++x) {
        const float len = static_cast<float>(cv::norm(n[x]));
        n[x] = (r[x][2] != 0 && len > 1e-6f) ? n[x] / len : cv::Vec3f(0, 0, 0);
      }
    }
  });
  return smooth;
}

}  // namespace clutterseg
