// Per-object outputs: statistics, support plane and the objects-only view.
#pragma once

#include <optional>

#include "clutterseg/params.hpp"
#include "clutterseg/support.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Pixel count, centroid and PCA-oriented box per object (transformed by camera.camera_to_robot),
// its patches and cut cost. object_labels is CV_32S 1..M.
std::vector<Object> describe_objects(const cv::Mat& object_labels, const cv::Mat& points,
                                     const std::vector<int>& object_of_patch,
                                     const std::vector<float>& cut_cost, const Camera& camera);

// Marks objects[i].support (it holds a table patch, Patch::table) and .background (walls and far
// surfaces: mostly higher than max_height above the table or below it, mostly not over the table's
// visible region, or a large flat object perpendicular to the table, unless it stands on the table in
// front of a farther surface: Params::Support::wall_hides_share, looked for within reach_px pixels,
// already scaled).
void classify_objects(std::vector<Object>& objects, const std::vector<Patch>& patches, const cv::Mat& object_labels,
                      const cv::Mat& points, const Support& support, const Params::Support& params, int reach_px);

// Copy of object_labels with support and background objects set to 0 and the rest renumbered 1..K in
// the order of their ids, or with their ids kept when keep_ids (tracked ids, Params::Tracking).
cv::Mat objects_only(const cv::Mat& object_labels, const std::vector<Object>& objects, bool keep_ids = false);

}  // namespace clutterseg
