// Paper c): surface patches = connected components of non-edge pixels, with per-patch statistics.
#pragma once

#include "clutterseg/normals.hpp"
#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

struct Patches {
  cv::Mat labels;              // CV_32S, patch id 1..N, 0 = edge or dropped
  std::vector<Patch> patches;  // patches[i].id == i + 1
};

// 4-connected components of the non-edge pixels (edges: CV_8U, non-zero = edge), numbered 1..N in
// raster order of their first pixel, as cv::connectedComponents numbers them; components smaller than
// min_size (already scaled to the resolution) are dropped. Statistics per patch from the depth (CV_32F metres; the centroid of
// the points depth_to_points gives) and the normals.
Patches extract_patches(const cv::Mat& edges, const cv::Mat& depth, const Camera& camera,
                        const NormalPlanes& normals, const Params::Patches& params, int min_size);

// extract_patches on `edges` after edge pixels were added inside some of `previous`'s patches (the table cut,
// the split at planes; never removed): the same result, but a patch no new edge pixel touched keeps its
// statistics instead of being measured again.
Patches update_patches(Patches previous, const cv::Mat& edges, const cv::Mat& depth, const Camera& camera,
                       const NormalPlanes& normals, const Params::Patches& params, int min_size);

// Where a marked pixel (mark: CV_8U, non-zero) meets an unmarked pixel of its patch, both become edge
// pixels in `edges`: the marked and unmarked parts of a patch are no longer 4-connected, and
// update_patches makes them patches of their own. The cuts of support.hpp, seams.hpp and cutfree.hpp.
void separate_marked(cv::Mat& edges, const cv::Mat& mark, const cv::Mat& patch_labels);

// One run of a connected component along an image row: columns [x0, x1) of row y.
struct LabelRun {
  int component, y, x0, x1;
};

// The runs of zero pixels of `edges` (CV_8U), row after row, and their 4-connected components, numbered
// 1, 2, ... in raster order of their first pixel, as cv::connectedComponents numbers them (the patches
// before the size limit). Appends to `runs`; returns the number of components plus one (0 is the edges).
int label_runs(const cv::Mat& edges, std::vector<LabelRun>& runs);

// The bin of a unit normal (x, y, z) in the (x, y) histogram of normals: bins x bins cells over [-1, 1]^2.
inline int normal_bin(float x, float y, int bins) {
  auto bin = [bins](float c) { return std::clamp(static_cast<int>((c + 1.f) * 0.5f * bins), 0, bins - 1); };
  return bin(y) * bins + bin(x);
}

}  // namespace clutterseg
