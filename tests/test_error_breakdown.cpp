// The error breakdown of `clutterseg eval` on label images whose causes are counted by hand. Images are
// 100x100: the boundary tolerance is ceil(0.003 * 141.4) = 1 px, so the band around a ground-truth
// boundary is the boundary ring and the ring next to it on either side (a 3x3 cross).
#include <gtest/gtest.h>

#include "clutterseg/error_breakdown.hpp"

#include <cmath>
#include <limits>

using namespace clutterseg;

namespace {

cv::Mat blank() { return cv::Mat(100, 100, CV_32S, cv::Scalar(0)); }
cv::Mat with(cv::Mat labels, const cv::Rect& r, int id) {
  labels(r).setTo(id);
  return labels;
}
ErrorBreakdown breakdown(const cv::Mat& gt, const cv::Mat& pred) {
  return error_breakdown(gt, pred, score_frame(gt, pred).matches);
}
void expect_shares_sum_to_one(const ErrorBreakdown& b) {
  EXPECT_NEAR(b.kept + b.boundary + b.dropped + b.split + b.merged, 1.0, 1e-12);
  EXPECT_NEAR(b.correct + b.boundary_p + b.background + b.merged_p + b.extra, 1.0, 1e-12);
}

// A 20x20 square has 76 ring pixels, 68 in the ring inside it and 256 beyond the band.
const cv::Rect kA(10, 10, 20, 20), kB(30, 10, 20, 20);

}  // namespace

TEST(ErrorBreakdown, PerfectSegmentationKeepsEverything) {
  const cv::Mat gt = with(with(blank(), kA, 1), kB, 2);
  const ErrorBreakdown b = breakdown(gt, gt);
  EXPECT_DOUBLE_EQ(b.kept, 1);
  EXPECT_DOUBLE_EQ(b.correct, 1);
  EXPECT_EQ(b.merged_objects + b.split_objects + b.missed_objects, 0);
}

TEST(ErrorBreakdown, TwoTouchingObjectsInOneSegmentAreAMerge) {
  const cv::Mat gt = with(with(blank(), kA, 1), kB, 2);
  const cv::Mat pred = with(blank(), kA | kB, 5);
  const ErrorBreakdown b = breakdown(gt, pred);
  // One object keeps its 400 px; the other's 400 px are 144 within the band and 256 merged.
  EXPECT_DOUBLE_EQ(b.kept, 400.0 / 800);
  EXPECT_DOUBLE_EQ(b.boundary, 144.0 / 800);
  EXPECT_DOUBLE_EQ(b.merged, 256.0 / 800);
  EXPECT_DOUBLE_EQ(b.correct, 400.0 / 800);
  EXPECT_DOUBLE_EQ(b.merged_p, 256.0 / 800);
  EXPECT_EQ(b.merged_objects, 2);
  EXPECT_EQ(b.missed_objects, 1);
  EXPECT_EQ(b.split_objects, 0);
  expect_shares_sum_to_one(b);
}

TEST(ErrorBreakdown, TableKeptWithAnObjectIsBackgroundNotAMerge) {
  const cv::Mat gt = with(blank(), kA, 1);
  const cv::Mat pred = with(blank(), cv::Rect(10, 10, 20, 40), 3);  // the object and 20x20 of table below it
  const ErrorBreakdown b = breakdown(gt, pred);
  // Table pixels: the row below the object is in the band (20 px), the other 380 are background.
  EXPECT_DOUBLE_EQ(b.kept, 1);
  EXPECT_DOUBLE_EQ(b.background, 380.0 / 800);
  EXPECT_DOUBLE_EQ(b.boundary_p, 20.0 / 800);
  EXPECT_EQ(b.merged_objects, 0);
  expect_shares_sum_to_one(b);
}

TEST(ErrorBreakdown, HalfAnObjectInAnotherSegmentIsASplitAndAHoleIsDropped) {
  const cv::Mat gt = with(blank(), cv::Rect(10, 10, 40, 20), 1);  // 800 px
  cv::Mat pred = with(with(blank(), cv::Rect(10, 10, 30, 20), 1), cv::Rect(40, 10, 10, 20), 2);
  pred(cv::Rect(20, 15, 5, 5)).setTo(0);  // a hole of 25 px well inside the object
  const ErrorBreakdown b = breakdown(gt, pred);
  // The 10x20 piece: its pixels in the object's ring (x = 49, y = 10 and y = 29) or next to it are in
  // the band: columns 40..47 keep 16 rows out of the band, column 48 none, column 49 none -> 8 * 16 = 128.
  EXPECT_DOUBLE_EQ(b.split, 128.0 / 800);
  EXPECT_DOUBLE_EQ(b.dropped, 25.0 / 800);
  EXPECT_DOUBLE_EQ(b.extra, 128.0 / 775);
  EXPECT_EQ(b.split_objects, 1);
  expect_shares_sum_to_one(b);
}

TEST(ErrorBreakdown, ASegmentOnNoObjectIsExtra) {
  const cv::Mat gt = with(blank(), kA, 1);
  const cv::Mat pred = with(with(blank(), kA, 1), cv::Rect(60, 60, 10, 10), 2);
  const ErrorBreakdown b = breakdown(gt, pred);
  EXPECT_DOUBLE_EQ(b.kept, 1);
  EXPECT_DOUBLE_EQ(b.extra, 100.0 / 500);
  expect_shares_sum_to_one(b);
}

TEST(ErrorBreakdown, EmptyPredictionDropsEverythingAndHasNoPrecisionToLose) {
  const cv::Mat gt = with(blank(), kA, 1);
  const ErrorBreakdown b = breakdown(gt, blank());
  EXPECT_DOUBLE_EQ(b.dropped + b.boundary, 1);
  EXPECT_DOUBLE_EQ(b.correct, 0);
  EXPECT_EQ(b.missed_objects, 1);
}

TEST(ErrorBreakdown, LostPixelsWithoutDepthAreCountedBesideTheirCause) {
  const cv::Mat gt = with(blank(), cv::Rect(10, 10, 40, 20), 1);  // 800 px
  cv::Mat pred = with(blank(), cv::Rect(10, 10, 40, 20), 1);
  pred(cv::Rect(20, 15, 5, 5)).setTo(0);  // 25 px dropped, well inside the object
  cv::Mat depth(gt.size(), CV_16U, cv::Scalar(1000));
  depth(cv::Rect(20, 15, 5, 2)).setTo(0);  // 10 of them without depth
  depth(cv::Rect(30, 15, 5, 5)).setTo(0);  // and 25 kept pixels without depth: not lost, not counted
  const ErrorBreakdown b = error_breakdown(gt, pred, score_frame(gt, pred).matches, depth);
  EXPECT_DOUBLE_EQ(b.dropped, 25.0 / 800);
  EXPECT_DOUBLE_EQ(b.no_depth, 10.0 / 800);
  expect_shares_sum_to_one(b);  // the partition is unchanged
  cv::Mat metres;
  depth.convertTo(metres, CV_32F, 0.001);
  metres.setTo(std::numeric_limits<float>::quiet_NaN(), depth == 0);  // float depth: NaN = none
  EXPECT_DOUBLE_EQ(error_breakdown(gt, pred, score_frame(gt, pred).matches, metres).no_depth, 10.0 / 800);
  EXPECT_TRUE(std::isnan(error_breakdown(gt, pred, score_frame(gt, pred).matches).no_depth));
  EXPECT_THROW(error_breakdown(gt, pred, score_frame(gt, pred).matches, depth(cv::Rect(0, 0, 50, 50))), Error);
}

TEST(ErrorBreakdown, TpLimitIsTheMeanMeasuredShareOfTheObjects) {
  // Two objects: one fully measured, one with a quarter of it in a hole (the projector's shadow). A method
  // that labels exactly the measured pixels scores the paper's tp (1 + 0.75) / 2, whatever it predicts.
  cv::Mat gt = with(blank(), cv::Rect(10, 10, 20, 20), 1);  // 400 px
  gt = with(gt, cv::Rect(50, 10, 20, 20), 2);                // 400 px
  cv::Mat depth(gt.size(), CV_16U, cv::Scalar(1000));
  depth(cv::Rect(50, 10, 5, 20)).setTo(0);  // 100 px of object 2
  depth(cv::Rect(0, 40, 30, 5)).setTo(0);   // a hole on the table: no object's, no effect
  cv::Mat measured_only = gt.clone();
  measured_only.setTo(0, depth == 0);
  for (const cv::Mat& pred : {gt, measured_only, blank()}) {
    const ErrorBreakdown b = error_breakdown(gt, pred, score_frame(gt, pred).matches, depth);
    EXPECT_DOUBLE_EQ(b.tp_limit, 0.875);
  }
  EXPECT_DOUBLE_EQ(score_frame(gt, measured_only).tp, 0.875);  // the limit is that method's tp
  EXPECT_TRUE(std::isnan(error_breakdown(gt, gt, score_frame(gt, gt).matches).tp_limit));  // no depth given
}
