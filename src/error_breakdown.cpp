#include "clutterseg/error_breakdown.hpp"

#include <algorithm>
#include <map>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

namespace clutterseg {

namespace {

cv::Mat int_labels(const cv::Mat& image, const char* what) {
  if (image.empty() || image.channels() != 1 || (image.depth() != CV_32S && image.depth() != CV_16U && image.depth() != CV_8U))
    throw Error(std::string(what) + ": label image must be one channel of integer ids");
  if (image.depth() == CV_32S) return image;
  cv::Mat out;
  image.convertTo(out, CV_32S);
  return out;
}

}  // namespace

std::array<double, 12> breakdown_values(const ErrorBreakdown& b) {
  return {b.kept, b.boundary, b.dropped, b.split, b.merged, b.no_depth, b.tp_limit,
          b.correct, b.boundary_p, b.background, b.merged_p, b.extra};
}

ErrorBreakdown error_breakdown(const cv::Mat& ground_truth, const cv::Mat& prediction,
                               const std::vector<std::pair<int, int>>& matches, const cv::Mat& depth) {
  const cv::Mat gt = int_labels(ground_truth, "ground truth"), pred = int_labels(prediction, "prediction");
  if (gt.size() != pred.size()) throw Error("error breakdown: the ground truth and the prediction differ in size");
  if (!depth.empty() && (depth.size() != gt.size() || depth.channels() != 1 || (depth.depth() != CV_16U && depth.depth() != CV_32F)))
    throw Error("error breakdown: the depth image must be one channel of uint16 or float of the labels' size");
  // 255 where there is no measurement (0, or NaN for float depth: NaN > 0 is false).
  cv::Mat unmeasured;
  if (!depth.empty()) unmeasured = depth.depth() == CV_16U ? (depth == 0) : ~(depth > 0);
  std::unordered_map<int, int> pred_of_gt, gt_of_pred;
  for (const auto& [g, p] : matches) {
    pred_of_gt[g] = p;
    gt_of_pred[p] = g;
  }
  // Pixels within the tolerance of a ground-truth object boundary (on either side of it).
  const int radius = boundary_tolerance_px(gt.size());
  cv::Mat band;
  cv::dilate(object_boundaries(gt), band, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * radius + 1, 2 * radius + 1}),
             cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));

  enum { kKept, kBoundary, kDropped, kSplit, kMerged, kCorrect, kBoundaryP, kBackground, kMergedP, kExtra, kNoDepth, kCount };
  std::array<long, kCount> count{};
  std::map<std::pair<int, int>, long> overlap;  // (gt id, pred id) -> pixels: bounded by the pixels
  std::map<int, long> gt_area, gt_measured;
  const auto matched = [](const std::unordered_map<int, int>& m, int id) {
    const auto it = m.find(id);
    return it == m.end() ? 0 : it->second;
  };
  for (int y = 0; y < gt.rows; ++y) {
    const int* g = gt.ptr<int>(y);
    const int* p = pred.ptr<int>(y);
    const uchar* near_boundary = band.ptr<uchar>(y);
    const uchar* no_measurement = unmeasured.empty() ? nullptr : unmeasured.ptr<uchar>(y);
    for (int x = 0; x < gt.cols; ++x) {
      if (g[x] != 0) {  // where a ground-truth pixel went
        ++gt_area[g[x]];
        if (no_measurement && !no_measurement[x]) ++gt_measured[g[x]];
        if (p[x] != 0) ++overlap[{g[x], p[x]}];
        const int own = matched(pred_of_gt, g[x]);
        const bool kept = own != 0 && p[x] == own;
        if (!kept && no_measurement && no_measurement[x]) ++count[kNoDepth];
        if (kept) ++count[kKept];
        else if (near_boundary[x]) ++count[kBoundary];
        else if (p[x] == 0) ++count[kDropped];
        else if (matched(gt_of_pred, p[x]) != 0) ++count[kMerged];
        else ++count[kSplit];
      }
      if (p[x] != 0) {  // what a predicted pixel covers
        const int own = matched(gt_of_pred, p[x]);
        if (own != 0 && g[x] == own) ++count[kCorrect];
        else if (near_boundary[x]) ++count[kBoundaryP];
        else if (own == 0) ++count[kExtra];
        else if (g[x] == 0) ++count[kBackground];
        else ++count[kMergedP];
      }
    }
  }
  ErrorBreakdown b;
  const double gt_pixels = static_cast<double>(count[kKept] + count[kBoundary] + count[kDropped] + count[kSplit] + count[kMerged]);
  const double pred_pixels = static_cast<double>(count[kCorrect] + count[kBoundaryP] + count[kBackground] + count[kMergedP] + count[kExtra]);
  if (gt_pixels > 0) {
    b.kept = count[kKept] / gt_pixels;
    b.boundary = count[kBoundary] / gt_pixels;
    b.dropped = count[kDropped] / gt_pixels;
    b.split = count[kSplit] / gt_pixels;
    b.merged = count[kMerged] / gt_pixels;
    if (!unmeasured.empty()) {
      b.no_depth = count[kNoDepth] / gt_pixels;
      double share_sum = 0;
      for (const auto& [g, area] : gt_area) share_sum += static_cast<double>(gt_measured[g]) / static_cast<double>(area);
      b.tp_limit = share_sum / static_cast<double>(gt_area.size());
    }
    // An empty prediction has no precision to lose (score_frame gives it P = 0 by convention).
    b.correct = b.boundary_p = b.background = b.merged_p = b.extra = 0;
  }
  if (pred_pixels > 0 && gt_pixels > 0) {
    b.correct = count[kCorrect] / pred_pixels;
    b.boundary_p = count[kBoundaryP] / pred_pixels;
    b.background = count[kBackground] / pred_pixels;
    b.merged_p = count[kMergedP] / pred_pixels;
    b.extra = count[kExtra] / pred_pixels;
  }
  // Events: the largest segment of each object (the paper's S_i, smallest id on ties), and its pieces.
  std::map<int, int> largest_segment;
  std::map<int, int> pieces;
  for (const auto& [ids, pixels] : overlap) {
    const auto [g, p] = ids;
    auto it = largest_segment.find(g);
    if (it == largest_segment.end() || pixels > overlap[{g, it->second}]) largest_segment[g] = p;
    if (pixels >= 0.1 * gt_area[g]) ++pieces[g];
  }
  std::map<int, int> objects_of_segment;
  for (const auto& [g, p] : largest_segment) ++objects_of_segment[p];
  for (const auto& [g, area] : gt_area) {
    const auto it = largest_segment.find(g);
    if (it != largest_segment.end() && objects_of_segment[it->second] > 1) ++b.merged_objects;
    if (pieces[g] > 1) ++b.split_objects;
    if (pred_of_gt.find(g) == pred_of_gt.end()) ++b.missed_objects;
  }
  return b;
}

}  // namespace clutterseg
