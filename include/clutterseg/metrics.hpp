// Segmentation quality against ground truth (SPEC Sec. 4): the paper's per-object scores (OSD) and the
// unseen-object instance segmentation scores (UOIS: Overlap and Boundary P/R/F, %>=75), side by side.
// Pure functions on label images: CV_32S (or CV_16U / CV_8U) ids, 0 = not an object on both sides.
#pragma once

#include <array>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "clutterseg/types.hpp"

namespace clutterseg {

// Scores of one image, as fractions in [0, 1]. NaN when undefined: every score of an image without
// ground-truth objects (there is nothing to find; the image is left out of the means).
struct FrameScores {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  int gt_objects = 0;      // ids != 0 in the ground truth
  int pred_objects = 0;    // ids != 0 in the prediction
  int matched = 0;         // Hungarian pairs with overlap (F > 0)

  // Paper (Ückermann et al. Sec. III-A): for each ground-truth object R_i, S_i = the predicted segment
  // with the largest overlap (smallest id on ties); means over the n ground-truth objects.
  double tp = kNaN;        // mean |R_i & S_i| / |R_i|
  double fp = kNaN;        // mean |S_i \ R_i| / |S_i|; a missed object (no S_i) adds 0
  double fn = kNaN;        // 1 - tp

  // UOIS (Xie et al. 2019): one-to-one Hungarian matching maximising the summed pairwise F.
  double overlap_p = kNaN, overlap_r = kNaN, overlap_f = kNaN;
  double boundary_p = kNaN, boundary_r = kNaN, boundary_f = kNaN;
  double detected_75 = kNaN;  // share of ground-truth objects whose matched F > 0.75 ("%>=75")
  std::vector<std::pair<int, int>> matches;  // the UOIS matching: (ground-truth id, predicted id), F > 0

  bool scored() const { return gt_objects > 0; }
};

// Names of the scores in the order of `score_values`, for tables, CSV and JSON.
inline constexpr std::array<const char*, 10> kScoreNames = {
    "tp", "fp", "fn", "overlap_p", "overlap_r", "overlap_f", "boundary_p", "boundary_r", "boundary_f", "detected_75"};
std::array<double, 10> score_values(const FrameScores& s);

// Both families for one image. Throws Error when the two images differ in size or are not
// single-channel integer label images.
FrameScores score_frame(const cv::Mat& ground_truth, const cv::Mat& prediction);

// Boundary tolerance of the UOIS Boundary scores: ceil(0.003 * image diagonal) pixels (3 at 640x480).
int boundary_tolerance_px(cv::Size size);

// Boundary pixels of every object: a pixel whose 4-neighbour inside the image carries another id.
// CV_8U, 255 = boundary of the object the pixel belongs to; label 0 pixels are never boundary.
cv::Mat object_boundaries(const cv::Mat& labels);

// Maximum-weight one-to-one assignment (Hungarian algorithm, O(n^2 m)) for a rows x cols matrix of
// weights (rows may differ from cols). Returns, per row, the assigned column or -1 (more rows than
// columns). Every row is assigned when rows <= cols.
std::vector<int> max_weight_assignment(const std::vector<std::vector<double>>& weight);

// Mean and population standard deviation of the finite values (NaN ignored); count = values used.
struct MeanStd {
  double mean = FrameScores::kNaN, std = FrameScores::kNaN;
  int count = 0;
};
MeanStd mean_std(const std::vector<double>& values);

}  // namespace clutterseg
