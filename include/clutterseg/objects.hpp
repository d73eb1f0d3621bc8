// Per-object outputs: statistics, support plane and the objects-only view.
#pragma once

#include <optional>

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Pixel count, centroid and PCA-oriented box per object (transformed by camera.camera_to_robot),
// its patches and cut cost. object_labels is CV_32S 1..M.
std::vector<Object> describe_objects(const cv::Mat& object_labels, const cv::Mat& points,
                                     const std::vector<int>& object_of_patch,
                                     const std::vector<float>& cut_cost, const Camera& camera);

// The table: the large flat patch with the most object mass resting on its camera-facing side.
// Marks objects[i].support / .background and returns the plane (camera frame) if one is found.
std::optional<Plane> find_support(std::vector<Object>& objects, const std::vector<Patch>& patches,
                                  const cv::Mat& object_labels, const cv::Mat& points,
                                  const Params::Support& params);

// Objects the edges or links did not separate from the table: pixels of support objects standing
// clear of the table plane (more than plane_band above it, at most max_height) form 8-connected groups;
// each group of at least min_px pixels becomes a new object (labels changed in place, objects
// appended with their statistics). Returns the number of new objects.
int split_support(cv::Mat& object_labels, std::vector<Object>& objects, const Plane& table, const cv::Mat& points,
                  const Params::Support& params, int min_px, const Camera& camera);

// Copy of object_labels with support and background objects set to 0 and the rest renumbered 1..K.
cv::Mat objects_only(const cv::Mat& object_labels, const std::vector<Object>& objects);

}  // namespace clutterseg
