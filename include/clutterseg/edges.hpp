// Paper b): surface-normal edges.
#pragma once

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Mean over the 8 neighbour directions (at distance `step`) of |n(p) . n(q)|; 1 on flat surfaces,
// smaller at creases. Pixels without a normal get 0; neighbours without a normal count as 0.
cv::Mat normal_edge_value(const cv::Mat& normals, int step);

// Binary edge image (CV_8U, 255 = edge): edge value below theta, no measurement, or a depth jump
// (relative to z, see relative_jump_limit) to any of the 8 neighbours at distance `step`.
cv::Mat edge_mask(const cv::Mat& edge_value, const cv::Mat& points, double theta, int step,
                  float jump_limit);

}  // namespace clutterseg
