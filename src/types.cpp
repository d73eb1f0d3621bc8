#include "clutterseg/types.hpp"

#include <cmath>

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
