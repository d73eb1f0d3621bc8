// Occlusion check shared by co-planarity (g) and curvature matching (h): is the gap between two
// surface points explained by something in front of it, rather than by background behind it?
#pragma once

#include "clutterseg/types.hpp"

namespace clutterseg {

// Samples the straight 3D segment from a to b (camera frame) at every image pixel it crosses and
// returns the share of samples whose measured point lies behind the segment by more than `tolerance`
// metres. Invalid pixels never count against. Returns 0 when no valid sample exists.
double behind_fraction(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const cv::Mat& points,
                       const Camera& camera, double tolerance);

}  // namespace clutterseg
