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

}  // namespace clutterseg
