#include "clutterseg/occlusion.hpp"

#include <algorithm>
#include <cmath>

namespace clutterseg {

GapView view_gap(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const cv::Mat& points, const Camera& camera,
                 double tolerance) {
  if (points.empty() || a.z() <= 0 || b.z() <= 0) return {};
  if (points.type() != CV_32FC3) throw Error("view_gap: points must be a CV_32FC3 image");
  const double fx = camera.fx, fy = camera.fy, cx = camera.cx, cy = camera.cy;
  const double ua = fx * a.x() / a.z() + cx, va = fy * a.y() / a.z() + cy;
  const double ub = fx * b.x() / b.z() + cx, vb = fy * b.y() / b.z() + cy;
  // One sample per pixel step along the longer image axis, clamped to the image size (samples
  // outside the image are skipped), so the loop is bounded whatever the endpoints.
  const double du = ub - ua, dv = vb - va, length2 = du * du + dv * dv;
  const double span = std::max(std::abs(du), std::abs(dv));
  const int max_steps = points.cols + points.rows;
  const int steps = std::clamp(static_cast<int>(std::ceil(span - 1e-6)), 1, max_steps);
  const double inv_za = 1.0 / a.z(), inv_zb = 1.0 / b.z();

  int valid = 0, behind = 0, in_front = 0;
  for (int k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / steps;
    const int u = static_cast<int>(std::lround(ua + t * du));
    const int v = static_cast<int>(std::lround(va + t * dv));
    if (u < 0 || v < 0 || u >= points.cols || v >= points.rows) continue;
    const cv::Vec3f& measured = points.at<cv::Vec3f>(v, u);
    if (!(measured[2] > 0)) continue;  // no measurement: never counts against
    // The segment where this pixel's centre sees it (rounding moved us off t by up to half a pixel);
    // perspective-correct: 1/z is linear along the image line.
    const double s = length2 > 0 ? std::clamp(((u - ua) * du + (v - va) * dv) / length2, 0.0, 1.0) : 0.0;
    const double z_segment = 1.0 / (inv_za + s * (inv_zb - inv_za));
    // Compare ranges along the pixel's ray, so the tolerance is a distance in metres.
    const double ray = std::sqrt(1.0 + std::pow((u - cx) / fx, 2) + std::pow((v - cy) / fy, 2));
    ++valid;
    const double offset = (measured[2] - z_segment) * ray;
    behind += offset > tolerance;
    in_front += offset < -tolerance;
  }
  if (!valid) return {};
  return {static_cast<double>(behind) / valid, static_cast<double>(in_front) / valid};
}

double behind_fraction(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const cv::Mat& points,
                       const Camera& camera, double tolerance) {
  return view_gap(a, b, points, camera, tolerance).behind;
}

}  // namespace clutterseg
