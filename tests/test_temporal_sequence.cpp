// Temporal smoothing on the synthetic `sequence` preset through the Kinect v1 model: one object moves
// across a static table. The static table's depth noise falls with the window; the moving object keeps
// its newest depth (no motion blur). Prints the figures quoted in docs/PRESEGMENTATION.md.
#include <gtest/gtest.h>

#include <cstdio>

#include "clutterseg/smoothing.hpp"
#include "clutterseg/synth/dataset.hpp"

using namespace clutterseg;

namespace {
// Standard deviation of (depth - truth) over `mask`, in mm.
double error_mm(const cv::Mat& depth, const cv::Mat& truth, const cv::Mat& mask) {
  cv::Scalar mean, sd;
  cv::meanStdDev(depth - truth, mean, sd, mask);
  return sd[0] * 1000;
}
}  // namespace

TEST(TemporalSequence, KinectNoiseOnTheTableFallsAndTheMovingObjectIsNotBlurred) {
  const Camera camera = synth::default_camera(640, 480);
  TemporalSmoother smoother;
  Params::Smoothing p;
  double table_raw = 0, table_smoothed = 0, object_raw = 0, object_smoothed = 0;
  for (int i = 0; i < 8; ++i) {
    const synth::SynthFrame f = synth::synthesize("sequence", 3, i, camera, synth::Sensor::KinectV1);
    const cv::Mat raw = median_depth(f.sensor.depth);
    const cv::Mat smoothed = smoother.push(raw, p);
    const cv::Mat& truth = f.sensor.true_depth;
    // Measured pixels within 3 cm of the truth (lateral edge noise and shadows are not depth noise).
    const cv::Mat near = (raw > 0) & (truth > 0) & (cv::abs(raw - truth) < 0.03);
    table_raw = error_mm(raw, truth, near & (f.sensor.labels == 0) & (truth < 1.6));
    table_smoothed = error_mm(smoothed, truth, near & (f.sensor.labels == 0) & (truth < 1.6));
    object_raw = error_mm(raw, truth, near & (f.sensor.labels > 0));
    object_smoothed = error_mm(smoothed, truth, near & (f.sensor.labels > 0));
  }
  std::printf("table noise: %.2f mm raw, %.2f mm after 6-frame smoothing; moving object: %.2f mm raw, %.2f mm smoothed\n",
              table_raw, table_smoothed, object_raw, object_smoothed);
  EXPECT_LT(table_smoothed, 0.55 * table_raw);          // 1/sqrt(6) = 0.41 at best
  EXPECT_LT(object_smoothed, 1.05 * object_raw);        // no blur: no worse than the newest frame
}
