// Paper h): curvature matching of curved patches by their normal histograms.
#pragma once

#include <optional>

#include "clutterseg/adjacency.hpp"
#include "clutterseg/normals.hpp"

namespace clutterseg {

// S(A, B) = sum_ij min(a_ij, b_ij), in [0, 1] (paper Eq. 3).
double histogram_similarity(const std::vector<float>& a, const std::vector<float>& b);

// Convexity of a curved patch from its normal histogram (paper Eq. 4, defined physically: a convex
// surface's normals turn away from its centre). +1 convex, -1 concave, 0 undecided.
int convexity(const Patch& patch, const cv::Mat& points, const NormalPlanes& normals, int bins);

// A cylinder through a curved surface: its axis is the direction its normals are all across (the least
// eigenvector of sum n n^T), its centre line where the normal lines meet in the plane across the axis (least
// squares), its radius the mean distance of the points to that line.
struct Cylinder {
  Eigen::Vector3d point, axis;
  double radius = 0;
  double distance(const Eigen::Vector3d& x) const {  // from the surface
    const Eigen::Vector3d d = x - point;
    return std::abs((d - d.dot(axis) * axis).norm() - radius);
  }
};

// The cylinder through `pixels` (at most ~512 of them read, with their normals), or none: fewer than 10 with a
// normal, normals not all within ~18 deg of across one direction, normals that barely turn (a plane), or a
// radius above 30 cm.
std::optional<Cylinder> fit_cylinder(const std::vector<int>& pixels, const cv::Mat& points, const NormalPlanes& normals);

struct CurvatureLink {
  PatchPair pair;
  Cue cue;  // CurvatureOpen or CurvatureOccluded
};

// Links between curved patches not already in `linked`: similar histograms (S > theta_h) and either
// image neighbours of opposite convexity whose centres of curvature agree within params.curvature.open_centre
// (open object; the centre test is beyond the paper), or a 3D line through both patches' peak-bin
// points that fits within line_fit and passes the occlusion check (occluded curved object). Beyond the
// paper, image neighbours of opposite convexity whatever their histograms whose normals meet at one
// centre or axis (params.curvature.concentric; an open object's outer wall and its inside), and concave
// patches, image neighbours or not, on one sphere or cylinder (params.curvature.split_inside; an open
// object's inside split by something standing in it).
std::vector<CurvatureLink> curvature_links(const std::vector<Patch>& patches,
                                           const std::vector<PatchPair>& linked,
                                           const cv::Mat& assigned_labels, const cv::Mat& points,
                                           const NormalPlanes& normals, const Camera& camera,
                                           const Params& params);

// Of the adjacent `pairs` (a concave crease between each), those whose two patches are both concave and lie
// on one sphere or cylinder within `share` (the split-inside test): a bowl's wall turning into its floor, one
// surface, not two objects touching (beyond the paper, Params::Curvature::inside_crease).
std::vector<PatchPair> creases_inside(const std::vector<Patch>& patches, const std::vector<PatchPair>& pairs,
                                      const cv::Mat& points, const NormalPlanes& normals, double share);

}  // namespace clutterseg
