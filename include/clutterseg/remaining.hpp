// Paper j): pixels that no patch took (bold edges, small objects) become objects or join one.
#pragma once

#include <optional>

#include "clutterseg/normals.hpp"
#include "clutterseg/occlusion.hpp"
#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// The table, for stage j): its patches take no remaining pixel standing clear of its plane.
struct TableHint {
  Plane plane;
  std::vector<char> table_patch;  // per 0-based patch index: a piece of the table
  double pixel_band = 0.005;      // clear of the plane: higher than plane_tolerance(pixel_band, z) [m]
};

// object_of_patch maps 0-based patch index to 0-based object index. Returns the object image
// (CV_32S, 1..M, 0 = no measurement, or an isolated segment smaller than tiny_px) after region-growing
// the unassigned valid pixels (grow_distance in 3D per pixel step, across runs of at most gap_px pixels
// without depth along the 8 directions; gap_px already scaled, 0 = 8-connected only) and
// applying the paper's five rules; new objects get ids after the existing ones. A segment of several
// objects' faces that is a face of its own (its normals differ from every neighbouring face's) joins the
// face it meets in a convex edge, and a segment seen behind its one face across depth jumps larger than
// params.occluded_jump, or before it and concave to it (params.in_front), is an object of its own (both beyond
// the paper; docs/OBJECTS.md). tiny_px is
// already scaled to the resolution. normals may be empty (no face-of-its-own rule). With `occlusion`, a
// segment that would be an object of its own but lies on the planes of another object's faces near it, with
// only nearer things between, joins that object (params.hidden_coplanar_band; without it, no such joins).
cv::Mat assign_remaining(const cv::Mat& assigned_labels, const std::vector<int>& object_of_patch,
                         int num_objects, const cv::Mat& points, const NormalPlanes& normals,
                         const Params::Remaining& params, int tiny_px, const std::optional<TableHint>& table = {},
                         const OcclusionCheck* occlusion = nullptr, int gap_px = 1);

}  // namespace clutterseg
