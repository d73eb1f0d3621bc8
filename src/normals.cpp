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
      float* p = points.ptr<float>(y);
      const float ry = (static_cast<float>(y) - cy) * ify;
      for (int x = 0; x < depth.cols; ++x) {  // (0,0,0) where z = 0
        p[3 * x] = (static_cast<float>(x) - cx) * ifx * z[x];
        p[3 * x + 1] = ry * z[x];
        p[3 * x + 2] = z[x];
      }
    }
  });
  return points;
}

float relative_jump_limit(const Params::Edges& params, int step, const Camera& camera) {
  // Lateral distance of pixels `step` apart at depth z is z * step / f.
  return static_cast<float>(params.jump_slope * step / std::min(camera.fx, camera.fy));
}

cv::Mat compute_normals(const cv::Mat& depth, const Camera& camera, int step, int ksize, float jump_limit) {
  const int rows = depth.rows, cols = depth.cols, s = step;
  // Zero padding: a neighbour outside the image is "no measurement", like a hole.
  cv::Mat padded;
  cv::copyMakeBorder(depth, padded, s, s, s, s, cv::BORDER_CONSTANT, cv::Scalar(0));
  std::vector<float> ray_x(static_cast<size_t>(cols + 2 * s));  // (u - cx) / fx per padded column
  for (int u = 0; u < cols + 2 * s; ++u) ray_x[static_cast<size_t>(u)] = static_cast<float>((u - s - camera.cx) / camera.fx);
  const auto ray_y = [&](int v) { return static_cast<float>((v - camera.cy) / camera.fy); };

  cv::Mat planes[3] = {cv::Mat(depth.size(), CV_32F), cv::Mat(depth.size(), CV_32F), cv::Mat(depth.size(), CV_32F)};
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const float* up = padded.ptr<float>(y) + s;  // padded row y + s - s
      const float* mid = padded.ptr<float>(y + s) + s;
      const float* down = padded.ptr<float>(y + 2 * s) + s;
      const float* rx = ray_x.data() + s;
      const float ry = ray_y(y), ry_up = ray_y(y - s), ry_down = ray_y(y + s);
      float* nx = planes[0].ptr<float>(y);
      float* ny = planes[1].ptr<float>(y);
      float* nz = planes[2].ptr<float>(y);
      // Branch-free so that it vectorises: each tangent spans the neighbours that continue the
      // surface (central difference), else one neighbour and the centre (one-sided), else nothing.
      for (int x = 0; x < cols; ++x) {
        const float z = mid[x], lim = jump_limit * z;
        const float zl = mid[x - s], zr = mid[x + s], zu = up[x], zd = down[x];
        const bool l = zl > 0 && std::abs(zl - z) <= lim, r = zr > 0 && std::abs(zr - z) <= lim;
        const bool u = zu > 0 && std::abs(zu - z) <= lim, d = zd > 0 && std::abs(zd - z) <= lim;
        const float px = rx[x] * z, py = ry * z;
        // Horizontal tangent a - b, vertical tangent c - e.
        const float ax = r ? rx[x + s] * zr : px, ay = r ? ry * zr : py, az = r ? zr : z;
        const float bx = l ? rx[x - s] * zl : px, by = l ? ry * zl : py, bz = l ? zl : z;
        const float cx = d ? rx[x] * zd : px, cy = d ? ry_down * zd : py, cz = d ? zd : z;
        const float ex = u ? rx[x] * zu : px, ey = u ? ry_up * zu : py, ez = u ? zu : z;
        const float tux = ax - bx, tuy = ay - by, tuz = az - bz;
        const float tvx = cx - ex, tvy = cy - ey, tvz = cz - ez;
        // tv x tu faces the camera for any surface seen from the front (x right, y down, z forward).
        const float n0 = tvy * tuz - tvz * tuy, n1 = tvz * tux - tvx * tuz, n2 = tvx * tuy - tvy * tux;
        const float len2 = n0 * n0 + n1 * n1 + n2 * n2;
        const float inv = (z > 0 && len2 > 0) ? 1.f / std::sqrt(len2) : 0.f;
        nx[x] = n0 * inv;
        ny[x] = n1 * inv;
        nz[x] = n2 * inv;
      }
    }
  });
  if (ksize > 1)
    for (auto& p : planes) cv::GaussianBlur(p, p, cv::Size(ksize, ksize), 0, 0, cv::BORDER_REPLICATE);
  parallel_for_rows(rows, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const float* z = depth.ptr<float>(y);
      float* nx = planes[0].ptr<float>(y);
      float* ny = planes[1].ptr<float>(y);
      float* nz = planes[2].ptr<float>(y);
      for (int x = 0; x < cols; ++x) {
        const float len2 = nx[x] * nx[x] + ny[x] * ny[x] + nz[x] * nz[x];
        const float inv = (z[x] > 0 && len2 > 1e-12f) ? 1.f / std::sqrt(len2) : 0.f;
        nx[x] *= inv;
        ny[x] *= inv;
        nz[x] *= inv;
      }
    }
  });
  cv::Mat normals;
  cv::merge(planes, 3, normals);
  return normals;
}

}  // namespace clutterseg
