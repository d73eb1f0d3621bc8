// Paper f/g): co-planar flat patches separated by occlusion.
#pragma once

#include "clutterseg/adjacency.hpp"

namespace clutterseg {

// Flat patches a and b span one plane (mean normals and `triples` random cross-patch point triples
// within angle_deg) and the gap between them is occluded (>= lines_pass of `lines` random lines pass
// behind_fraction). Beyond the paper, a patch whose histogram counts as curved but whose points are planar
// takes part too (planar_share), and then the lines must also cross an occluder (front_fraction).
// Deterministic for a given seed.
bool coplanar(const Patch& a, const Patch& b, const cv::Mat& points, const Camera& camera,
              const Params::Coplanarity& params, std::uint64_t seed);

// All co-planar pairs among the patches that take part (as above; no table patch) that are not already in
// `linked`.
std::vector<PatchPair> coplanar_pairs(const std::vector<Patch>& patches,
                                      const std::vector<PatchPair>& linked, const cv::Mat& points,
                                      const Camera& camera, const Params::Coplanarity& params,
                                      std::uint64_t seed);

}  // namespace clutterseg
