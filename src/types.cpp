#include "clutterseg/types.hpp"

#include <cmath>

#include "clutterseg/limits.hpp"

namespace clutterseg {

void check_camera(const Camera& camera, int width, int height, const std::string& what) {
  auto fail = [&](const std::string& problem) { throw Error(what + ": " + problem); };
  if (!(camera.fx > 0) || !(camera.fy > 0) || !std::isfinite(camera.fx) || !std::isfinite(camera.fy))
    fail("intrinsics need positive focal lengths fx, fy");
  if (camera.width != width || camera.height != height)
    fail("intrinsics are for " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
         " but the image is " + std::to_string(width) + "x" + std::to_string(height));
  if (!(camera.cx >= 0 && camera.cx <= width && camera.cy >= 0 && camera.cy <= height))
    fail("principal point (cx, cy) lies outside the image");
  if (!(camera.depth_unit_m > 0)) fail("depth_unit_m must be positive");
  check_frame_size(width, height, what);
  // Sizes in pixels grow with the focal length (PixelScale): a field of view below 1 degree is no depth
  // sensor and only makes kernels huge; above 175 degrees no pinhole model holds.
  const double kDeg = 3.14159265358979323846 / 180;
  const auto focal_bound = [&](double fov_deg, int pixels) { return pixels / (2 * std::tan(fov_deg * kDeg / 2)); };
  if (camera.fx > focal_bound(kMinFovDeg, width) || camera.fy > focal_bound(kMinFovDeg, height))
    fail("focal length fx " + std::to_string(camera.fx) + " / fy " + std::to_string(camera.fy) +
         " px gives a field of view below 1 degree for a " + std::to_string(width) + "x" + std::to_string(height) +
         " image (at most 57.3 x the image size)");
  if (camera.fx < focal_bound(kMaxFovDeg, width) || camera.fy < focal_bound(kMaxFovDeg, height))
    fail("focal length fx / fy gives a field of view above 175 degrees (at least 0.022 x the image size)");
  if (!(camera.depth_unit_m >= kMinDepthUnit && camera.depth_unit_m <= kMaxDepthUnit))
    fail("depth_unit_m " + std::to_string(camera.depth_unit_m) + " is outside [1e-6, 1] metres per step");
}

const char* to_string(Cue cue) {
  switch (cue) {
    case Cue::Adjacent: return "adjacent";
    case Cue::Coplanar: return "coplanar";
    case Cue::CurvatureOpen: return "curvature-open";
    case Cue::CurvatureOccluded: return "curvature-occluded";
    case Cue::AdjacentConcave: return "adjacent-concave";
  }
  return "unknown";
}

}  // namespace clutterseg
