// Both metric families (SPEC Sec. 4) on tiny label images whose scores are worked out by hand.
// Images are 10x10, so the boundary tolerance is ceil(0.003 * 14.1) = 1 px (a 3x3 cross).
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "clutterseg/metrics.hpp"

using namespace clutterseg;

namespace {

cv::Mat blank() { return cv::Mat(10, 10, CV_32S, cv::Scalar(0)); }

// Rows 2..5 of the image; `left` = columns 1..4 (16 px), `right` = columns 5..8 (16 px).
const cv::Rect kLeft(1, 2, 4, 4), kRight(5, 2, 4, 4), kBoth(1, 2, 8, 4);

cv::Mat with(cv::Mat labels, const cv::Rect& r, int id) {
  labels(r).setTo(id);
  return labels;
}

}  // namespace

TEST(Metrics, PerfectSegmentationScoresOneEverywhere) {
  const cv::Mat gt = with(with(blank(), kLeft, 1), kRight, 2);
  const FrameScores s = score_frame(gt, gt);
  EXPECT_EQ(s.gt_objects, 2);
  EXPECT_EQ(s.matched, 2);
  EXPECT_DOUBLE_EQ(s.tp, 1);
  EXPECT_DOUBLE_EQ(s.fp, 0);
  EXPECT_DOUBLE_EQ(s.fn, 0);
  for (double v : {s.overlap_p, s.overlap_r, s.overlap_f, s.boundary_p, s.boundary_r, s.boundary_f, s.detected_75})
    EXPECT_DOUBLE_EQ(v, 1);
}

TEST(Metrics, IdsThatDifferBetweenPredictionAndGroundTruthDoNotMatter) {
  const cv::Mat gt = with(with(blank(), kLeft, 1), kRight, 2);
  const cv::Mat pred = with(with(blank(), kLeft, 700), kRight, 3);  // other ids, other order
  cv::Mat pred16;
  pred.convertTo(pred16, CV_16U);  // a uint16 PNG as read from disk is accepted as it is
  const FrameScores s = score_frame(gt, pred16);
  EXPECT_DOUBLE_EQ(s.tp, 1);
  EXPECT_DOUBLE_EQ(s.overlap_f, 1);
  EXPECT_DOUBLE_EQ(s.boundary_f, 1);
  EXPECT_DOUBLE_EQ(s.detected_75, 1);
}

TEST(Metrics, OneObjectSplitInTwo) {
  const cv::Mat gt = with(blank(), kBoth, 1);
  const cv::Mat pred = with(with(blank(), kLeft, 1), kRight, 2);
  const FrameScores s = score_frame(gt, pred);
  // Paper: the better half (a tie, 16 of 32 px) is S; nothing of it lies outside R.
  EXPECT_DOUBLE_EQ(s.tp, 0.5);
  EXPECT_DOUBLE_EQ(s.fp, 0);
  EXPECT_DOUBLE_EQ(s.fn, 0.5);
  // UOIS: one half matched (F = 2*16/48 = 2/3 < 0.75): 16 of 32 predicted and of 32 true pixels.
  EXPECT_EQ(s.matched, 1);
  EXPECT_DOUBLE_EQ(s.overlap_p, 0.5);
  EXPECT_DOUBLE_EQ(s.overlap_r, 0.5);
  EXPECT_DOUBLE_EQ(s.overlap_f, 0.5);
  EXPECT_DOUBLE_EQ(s.detected_75, 0);
  // Boundaries: 12 + 12 predicted pixels, all 12 of the matched half lie within 1 px of the true
  // outline (its inner column touches rows 2 and 5); 20 true pixels, 12 of them near the half.
  EXPECT_DOUBLE_EQ(s.boundary_p, 12.0 / 24.0);
  EXPECT_DOUBLE_EQ(s.boundary_r, 12.0 / 20.0);
  EXPECT_NEAR(s.boundary_f, 2 * 0.5 * 0.6 / 1.1, 1e-12);
}

TEST(Metrics, TwoObjectsMerged) {
  const cv::Mat gt = with(with(blank(), kLeft, 1), kRight, 2);
  const cv::Mat pred = with(blank(), kBoth, 4);
  const FrameScores s = score_frame(gt, pred);
  // Paper: each object is fully inside the merged segment, which is half foreign to each.
  EXPECT_DOUBLE_EQ(s.tp, 1);
  EXPECT_DOUBLE_EQ(s.fp, 0.5);
  EXPECT_DOUBLE_EQ(s.fn, 0);
  // UOIS: the segment matches only one object, so half of it and half of the truth are matched.
  EXPECT_DOUBLE_EQ(s.overlap_p, 0.5);
  EXPECT_DOUBLE_EQ(s.overlap_r, 0.5);
  EXPECT_DOUBLE_EQ(s.detected_75, 0);
  EXPECT_DOUBLE_EQ(s.boundary_p, 12.0 / 20.0);
  EXPECT_DOUBLE_EQ(s.boundary_r, 12.0 / 24.0);
}

TEST(Metrics, MissedObject) {
  const cv::Mat gt = with(with(blank(), kLeft, 1), kRight, 2);
  const cv::Mat pred = with(blank(), kLeft, 5);
  const FrameScores s = score_frame(gt, pred);
  EXPECT_DOUBLE_EQ(s.tp, 0.5);  // (1 + 0) / 2
  EXPECT_DOUBLE_EQ(s.fp, 0);    // the missed object has no segment to be wrong
  EXPECT_DOUBLE_EQ(s.fn, 0.5);
  EXPECT_DOUBLE_EQ(s.overlap_p, 1);
  EXPECT_DOUBLE_EQ(s.overlap_r, 0.5);
  EXPECT_NEAR(s.overlap_f, 2.0 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.detected_75, 0.5);
  EXPECT_DOUBLE_EQ(s.boundary_p, 1);
  EXPECT_DOUBLE_EQ(s.boundary_r, 0.5);  // 12 of the 12 + 12 true outline pixels
}

TEST(Metrics, EmptyPredictionScoresZero) {
  const cv::Mat gt = with(blank(), kLeft, 1);
  const FrameScores s = score_frame(gt, blank());
  EXPECT_EQ(s.pred_objects, 0);
  EXPECT_DOUBLE_EQ(s.tp, 0);
  EXPECT_DOUBLE_EQ(s.fp, 0);
  EXPECT_DOUBLE_EQ(s.fn, 1);
  for (double v : {s.overlap_p, s.overlap_r, s.overlap_f, s.boundary_p, s.boundary_r, s.boundary_f, s.detected_75})
    EXPECT_DOUBLE_EQ(v, 0);
}

TEST(Metrics, ImageWithoutGroundTruthObjectsIsNotScored) {
  const FrameScores s = score_frame(blank(), with(blank(), kLeft, 1));
  EXPECT_FALSE(s.scored());
  for (double v : score_values(s)) EXPECT_TRUE(std::isnan(v));
}

TEST(Metrics, SegmentOnUnlabelledBackgroundCostsUoisPrecisionButNotPaperFp) {
  // Label 0 is "not an object" on both sides: a predicted object there is predicted object pixels that
  // match nothing, which only the UOIS precision sees.
  const cv::Mat gt = with(blank(), kLeft, 1);
  const cv::Mat pred = with(with(blank(), kLeft, 1), kRight, 2);
  const FrameScores s = score_frame(gt, pred);
  EXPECT_DOUBLE_EQ(s.tp, 1);
  EXPECT_DOUBLE_EQ(s.fp, 0);
  EXPECT_DOUBLE_EQ(s.overlap_p, 0.5);
  EXPECT_DOUBLE_EQ(s.overlap_r, 1);
}

TEST(Metrics, SizeMismatchAndBadTypesAreClearErrors) {
  const cv::Mat gt = with(blank(), kLeft, 1);
  try {
    score_frame(gt, cv::Mat(8, 10, CV_32S, cv::Scalar(0)));
    FAIL() << "no error for a size mismatch";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "prediction: size 10x8 differs from the ground truth 10x10");
  }
  EXPECT_THROW(score_frame(gt, cv::Mat(10, 10, CV_32F, cv::Scalar(0))), Error);
  EXPECT_THROW(score_frame(gt, cv::Mat(10, 10, CV_8UC3, cv::Scalar(0))), Error);
  EXPECT_THROW(score_frame(cv::Mat(), gt), Error);
}

TEST(Metrics, BoundaryToleranceFollowsTheImageDiagonal) {
  EXPECT_EQ(boundary_tolerance_px({640, 480}), 3);  // ceil(2.4)
  EXPECT_EQ(boundary_tolerance_px({320, 240}), 2);  // ceil(1.2)
  EXPECT_EQ(boundary_tolerance_px({10, 10}), 1);
}

TEST(Metrics, BoundaryOffByOnePixelStaysWithinToleranceAtVga) {
  // At 640x480 the tolerance is 3 px: an outline moved out by 1 px keeps boundary F near 1, while the
  // overlap loses the extra ring of pixels.
  cv::Mat gt(480, 640, CV_32S, cv::Scalar(0)), pred = gt.clone();
  gt(cv::Rect(100, 100, 50, 50)).setTo(1);
  pred(cv::Rect(99, 99, 52, 52)).setTo(1);
  const FrameScores s = score_frame(gt, pred);
  EXPECT_DOUBLE_EQ(s.boundary_p, 1);
  EXPECT_DOUBLE_EQ(s.boundary_r, 1);
  EXPECT_DOUBLE_EQ(s.overlap_p, 2500.0 / 2704.0);
  EXPECT_DOUBLE_EQ(s.overlap_r, 1);
}

TEST(Metrics, ObjectBoundariesAreTheInnerOutlineOfEachObject) {
  const cv::Mat labels = with(with(blank(), kLeft, 1), kRight, 2);
  const cv::Mat b = object_boundaries(labels);
  EXPECT_EQ(cv::countNonZero(b), 24);  // two 4x4 outlines, the shared border counted on both sides
  EXPECT_EQ(b.at<uchar>(3, 2), 0);     // interior
  EXPECT_EQ(b.at<uchar>(3, 4), 255);   // left object's column next to the right object
  EXPECT_EQ(b.at<uchar>(0, 0), 0);     // background is never boundary
}

TEST(Hungarian, BeatsGreedyMatching) {
  // Greedy takes 0.9 first and ends at 1.4; the best assignment sums 0.8 + 0.8 + 0.5 = 2.1.
  const std::vector<std::vector<double>> w = {{0.9, 0.8, 0.0}, {0.8, 0.0, 0.0}, {0.0, 0.0, 0.5}};
  EXPECT_EQ(max_weight_assignment(w), (std::vector<int>{1, 0, 2}));
}

TEST(Hungarian, RectangularMatricesAssignTheSmallerSide) {
  EXPECT_EQ(max_weight_assignment({{0.1, 0.9, 0.2}, {0.8, 0.7, 0.0}}), (std::vector<int>{1, 0}));
  EXPECT_EQ(max_weight_assignment({{0.1, 0.8}, {0.9, 0.7}, {0.2, 0.0}}), (std::vector<int>{1, 0, -1}));
  EXPECT_EQ(max_weight_assignment({{}, {}}), (std::vector<int>{-1, -1}));
  EXPECT_TRUE(max_weight_assignment({}).empty());
}

TEST(Hungarian, MatchesBruteForceOnRandomMatrices) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 60; ++trial) {
    const int rows = 1 + trial % 6, cols = 1 + (trial / 6) % 6;
    std::vector<std::vector<double>> w(rows, std::vector<double>(cols));
    for (auto& row : w)
      for (double& v : row) v = unit(rng) < 0.3 ? 0.0 : unit(rng);
    // Best total over every injective map of the smaller side into the larger.
    const int small = std::min(rows, cols), large = std::max(rows, cols);
    std::vector<int> perm(large);
    std::iota(perm.begin(), perm.end(), 0);
    double best = -1;
    do {
      double sum = 0;
      for (int k = 0; k < small; ++k) sum += rows <= cols ? w[k][perm[k]] : w[perm[k]][k];
      best = std::max(best, sum);
    } while (std::next_permutation(perm.begin(), perm.end()));
    const std::vector<int> a = max_weight_assignment(w);
    double got = 0;
    std::vector<int> used;
    for (int r = 0; r < rows; ++r)
      if (a[r] >= 0) {
        got += w[r][a[r]];
        used.push_back(a[r]);
      }
    std::sort(used.begin(), used.end());
    EXPECT_EQ(std::adjacent_find(used.begin(), used.end()), used.end()) << "a column used twice";
    EXPECT_EQ(static_cast<int>(used.size()), small);
    EXPECT_NEAR(got, best, 1e-12) << rows << "x" << cols << " trial " << trial;
  }
}

TEST(Metrics, MeanAndPopulationStdIgnoreUndefinedValues) {
  const MeanStd m = mean_std({0.5, FrameScores::kNaN, 1.0});
  EXPECT_EQ(m.count, 2);
  EXPECT_DOUBLE_EQ(m.mean, 0.75);
  EXPECT_DOUBLE_EQ(m.std, 0.25);
  EXPECT_TRUE(std::isnan(mean_std({}).mean));
}
