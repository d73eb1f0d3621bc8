// Paper j): pixels that no patch took (bold edges, small objects) become objects or join one.
#pragma once

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// object_of_patch maps 0-based patch index to 0-based object index. Returns the object image
// (CV_32S, 1..M, 0 = no measurement, or an isolated segment smaller than tiny_px) after region-growing
// the unassigned valid pixels (8-connected, grow_distance in 3D) and applying the paper's five rules;
// new objects get ids after the existing ones. tiny_px is already scaled to the resolution.
cv::Mat assign_remaining(const cv::Mat& assigned_labels, const std::vector<int>& object_of_patch,
                         int num_objects, const cv::Mat& points, const Params::Remaining& params,
                         int tiny_px, std::uint64_t seed);

}  // namespace clutterseg
