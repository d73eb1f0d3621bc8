// Beyond the paper: a patch split where a weak crease or a small step runs across it (a seam). Two boxes
// stacked with their fronts nearly flush, 3-10 mm apart, meet in a crease too shallow for the edge
// threshold: the normals dip there only to an edge value of 0.90-0.95, the edge band gets gaps, and one
// patch spans both fronts (synthetic stacked-boxes: 7 of the 9 frames with merged objects). Seen at a
// stricter threshold, the patch is two parts with a band of weaker pixels between them.
// docs/OBJECTS.md has the rule, docs/RESULTS.md (section 11) its measurements.
#pragma once

#include "clutterseg/normals.hpp"
#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

#include <optional>

namespace clutterseg {

// For every patch (core labels `patch_labels`, as extract_patches gives them): its pixels whose edge
// value is at least params.seam_theta, as 4-connected parts. A patch with two or more parts of at least
// `min_px` pixels (already scaled) is split: every pixel of the band between them (8-connected pixels of
// the patch in no such part, touching two or more of them) becomes an edge pixel in `edges`. Only when
// each part is nearly planar (its normals' mean angle to their mean within params.seam_spread_deg), or
// when the patch is table (Patch::table) and a part but its largest is not (fewer than 80 % of its points
// within half the support's plane_band of `table`): a curved surface's normals dip across it everywhere,
// a bowl's floor cut off its wall would be taken for table, and pieces of table need not be split.
// Returns the number of edge pixels added; 0 when params.seam_theta is 0.
int split_at_seams(cv::Mat& edges, const std::vector<Patch>& patches, const cv::Mat& patch_labels,
                   const cv::Mat& edge_value, const NormalPlanes& normals, const Params::Patches& params, int min_px,
                   const cv::Mat& points, const std::optional<Plane>& table, const Params::Support& support);

}  // namespace clutterseg
