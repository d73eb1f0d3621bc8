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

// What the segment from a to b crosses, sampled as behind_fraction does: the shares of the valid samples
// that lie behind it and in front of it by more than `tolerance` (both 0 when no valid sample exists).
struct GapView {
  double behind = 0;
  double in_front = 0;
};
GapView view_gap(const Eigen::Vector3f& a, const Eigen::Vector3f& b, const cv::Mat& points, const Camera& camera,
                 double tolerance);

// The check as a stage outside co-planarity runs it: the camera and co-planarity's settings
// (Params::Coplanarity::behind_tolerance and behind_fraction), so that both stages judge a gap alike.
struct OcclusionCheck {
  Camera camera;
  double tolerance;     // a sample is behind when deeper than the segment by this [m]
  double max_fraction;  // the gap is background when more samples than this share lie behind [-]
};

}  // namespace clutterseg
