// Why a segmentation scores what it scores: every pixel that costs Overlap precision or recall (SPEC
// Sec. 4, UOIS matching) is given one cause, so that a user sees whether objects were merged, pieces of
// table kept, objects split, pixels dropped, or only boundaries moved. docs/EVAL.md has the definitions.
#pragma once

#include <array>
#include <utility>
#include <vector>

#include "clutterseg/metrics.hpp"

namespace clutterseg {

struct ErrorBreakdown {
  static constexpr double kNaN = FrameScores::kNaN;
  // Ground-truth object pixels (shares sum to 1): where each went.
  double kept = kNaN;       // in the segment matched to its object (Overlap R)
  double boundary = kNaN;   // elsewhere, but within the boundary tolerance of a ground-truth boundary
  double dropped = kNaN;    // in no segment (label 0)
  double split = kNaN;      // in a segment matched to no object (an extra piece of it)
  double merged = kNaN;     // in the segment of another object (merged into it)
  double no_depth = kNaN;   // of the above but kept: the pixels without a depth measurement (not a cause of
                            // its own, a share of all ground-truth object pixels as well): what no depth-only
                            // method can place, the limit of Overlap R; NaN when no depth image is given
  double tp_limit = kNaN;   // the paper's tp of a method that labels exactly the pixels with depth of every
                            // object: the mean over the objects of their measured share (the tp a depth-only
                            // method reaches without guessing into holes); NaN when no depth image is given
  // Predicted object pixels (shares sum to 1): what each covers.
  double correct = kNaN;          // its segment's matched object (Overlap P)
  double boundary_p = kNaN;       // elsewhere, but within the boundary tolerance
  double background = kNaN;       // table or background (ground truth 0) inside a matched segment
  double merged_p = kNaN;         // another object inside a matched segment
  double extra = kNaN;            // in a segment matched to no object (unlabelled things, pieces)
  // Events, counted per frame.
  int merged_objects = 0;   // objects whose largest segment is also the largest segment of another object
  int split_objects = 0;    // objects with two or more segments of at least 10 % of the object each
  int missed_objects = 0;   // objects with no matched segment
};

inline constexpr std::array<const char*, 12> kBreakdownNames = {
    "kept", "boundary", "dropped", "split", "merged", "no_depth", "tp_limit",
    "correct", "boundary_p", "background", "merged_p", "extra"};
std::array<double, 12> breakdown_values(const ErrorBreakdown& b);

// The breakdown of one image, given the one-to-one matching of score_frame (FrameScores::matches):
// pixels within boundary_tolerance_px of a ground-truth object boundary that are wrong count as
// boundary errors whatever else they are. Images as for score_frame; `depth` (optional, CV_16U or CV_32F
// of the same size, 0 or NaN = no measurement) gives ErrorBreakdown::no_depth and tp_limit.
ErrorBreakdown error_breakdown(const cv::Mat& ground_truth, const cv::Mat& prediction,
                               const std::vector<std::pair<int, int>>& matches, const cv::Mat& depth = cv::Mat());

}  // namespace clutterseg
