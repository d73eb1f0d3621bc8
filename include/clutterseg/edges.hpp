// Paper b): surface-normal edges.
#pragma once

#include "clutterseg/normals.hpp"
#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Mean over the 8 neighbour directions (at distance `step`) of |n(p) . n(q)|; 1 on flat surfaces,
// smaller at creases. Pixels without a normal get 0; neighbours without a normal count as 0.
cv::Mat normal_edge_value(const cv::Mat& normals, int step);
cv::Mat normal_edge_value(const NormalPlanes& normals, int step);  // the same on planar normals

// Binary edge image (CV_8U, 255 = edge) from the edge value and the depth (CV_32F metres): edge value
// below theta, no measurement, or a depth jump
// to any of the 8 immediate neighbours larger than jump_limit * z (relative_jump_limit for step 1):
// discontinuities are tested between adjacent pixels, where the median keeps them sharp.
// Median of the edge value over the pixels with depth, read on a grid every `stride` pixels (deterministic);
// 1 when no pixel has depth. A measure of how noisy the normals are: most of a scene is smooth surface.
double median_edge_value(const cv::Mat& edge_value, const cv::Mat& depth, int stride = 8);

cv::Mat edge_mask(const cv::Mat& edge_value, const cv::Mat& depth, double theta, float jump_limit);

}  // namespace clutterseg
