// Paper d): adjacency of patches and assignment of edge pixels to the nearest patch.
#pragma once

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

using PatchPair = std::pair<int, int>;  // 0-based patch indices, first < second

// Where two patches meet: an edge pixel saw both, and these are the nearest pixel of each (the two
// seeds it kept). The contact cue (contact.hpp) reads the surfaces on both sides of the edge here.
struct Contact {
  int a = 0, b = 0;              // 0-based patch indices, a < b
  int pixel_a = 0, pixel_b = 0;  // linear pixel indices of a point of a and of b near the edge pixel
};

struct Assignment {
  cv::Mat labels;                  // CV_32S: patch id (1..N) per pixel, edge pixels included; 0 = none
  std::vector<PatchPair> adjacent; // every pair of patches seen together by one edge pixel; sorted, unique
  std::vector<Contact> contacts;   // one per edge pixel and pair it saw, sorted by pair (then edge pixel)
  std::vector<int> assigned;       // the edge pixels given a patch here (linear indices, any order)
};

// For every edge pixel with a valid point: the patch pixels within `radius_px` in the image whose 3D
// distance is below d_max; all patches seen become pairwise adjacent and the pixel joins the patch of
// the nearest such point. One pass; pixels seeing no patch stay 0. radius_px is already scaled.
Assignment assign_edge_pixels(const cv::Mat& patch_labels, const cv::Mat& points, int num_patches,
                              int radius_px, double d_max);

}  // namespace clutterseg
