// Paper a): organized 3D points and per-pixel surface normals.
#pragma once

#include <array>

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Back-projects depth (CV_32F metres, 0 = none) to CV_32FC3 camera-frame points; invalid = (0,0,0).
// The point of pixel (u, v) is (ray_x[u] * z, ray_y(v) * z, z), products in float, with the rays below.
cv::Mat depth_to_points(const cv::Mat& depth, const Camera& camera);
std::vector<float> ray_x(const Camera& camera, int cols);  // (u - cx) / fx for u = 0 .. cols - 1
inline float ray_y(const Camera& camera, int v) {           // (v - cy) / fy
  return (static_cast<float>(v) - static_cast<float>(camera.cy)) * static_cast<float>(1.0 / camera.fy);
}

// Largest |z(q) - z(p)| / z(p) between pixels `step` apart that is not a depth discontinuity.
float relative_jump_limit(const Params::Edges& params, int step, const Camera& camera);

// Normals as three CV_32F planes (x, y, z): every per-pixel loop reads them as plain float arrays, with
// no interleaving to undo. cv::merge gives the CV_32FC3 image.
using NormalPlanes = std::array<cv::Mat, 3>;

// Normals (unit, facing the camera; (0,0,0) = none) of the organized 3D points of `depth` (CV_32F
// metres): the cross product of the horizontal and vertical neighbour differences at distance `step`,
// then a Gaussian of size `ksize` and renormalisation. A difference across a depth discontinuity
// (jump_limit, relative to z) falls back to the one-sided difference. step and ksize are the scaled
// values (PixelScale).
NormalPlanes compute_normals(const cv::Mat& depth, const Camera& camera, int step, int ksize, float jump_limit);

}  // namespace clutterseg
