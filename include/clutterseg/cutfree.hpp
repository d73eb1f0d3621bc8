// Paper e): cut-free neighbours. Adjacent patches stay linked only if neither cuts the other.
#pragma once

#include "clutterseg/adjacency.hpp"

namespace clutterseg {

// True when a strict majority of `planes` RANSAC planes fitted to `cutter` leave `other` on one side
// (points within +-band are on the plane; a plane fails when the minority side holds more points than
// wrong_side_fraction of the smaller patch's point count). Deterministic for a given seed.
bool one_side_of(const Patch& cutter, const Patch& other, const cv::Mat& points,
                 const Params::CutFree& params, std::uint64_t seed);

// Keeps the pairs where each patch lies on one side of the other (or whose mean normals are within
// skip_angle_deg when skip_similar is set).
std::vector<PatchPair> cut_free_pairs(const std::vector<PatchPair>& adjacent,
                                      const std::vector<Patch>& patches, const cv::Mat& points,
                                      const Params::CutFree& params, std::uint64_t seed);

// Beyond the paper: a side face that holds surfaces of two objects. For every adjacent pair that failed
// the test (in `adjacent`, not in `linked`, both sorted) where one patch is a flat top (mean normal within
// 30 deg of `up`, 90 % of its points within plane_tolerance(band, z) of its least-squares plane) and the
// other a side (mean normal within 30 deg of horizontal) of at least 2 min_px pixels: when the top's
// plane leaves at least params.split_share of the side's points beyond that tolerance on either side,
// the side is split at the plane: the pixels where its two sides meet become edge pixels in `edges`
// (separate_marked), so that update_patches makes them patches of their own. The case: two stacked
// boxes' nearly flush fronts joined into one patch around the end of the thin top between them; the
// lower box's top cuts that patch, and no face of one box cuts another. `up`: the table's normal, or
// up_in_camera. Returns the pixels marked (0: edges unchanged). Deterministic (no random draws).
int split_cut_patches(cv::Mat& edges, const std::vector<PatchPair>& adjacent, const std::vector<PatchPair>& linked,
                      const std::vector<Patch>& patches, const cv::Mat& patch_labels, const cv::Mat& points,
                      const Params::CutFree& params, int min_px, const Eigen::Vector3f& up);

}  // namespace clutterseg
