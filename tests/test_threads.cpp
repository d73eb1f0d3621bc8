// Threads (issue 19): the row pool covers every row once, also with concurrent callers; the cross-frame
// Pipeline gives Segmenter's results byte for byte, in order, with the temporal window carried across
// frames, and reports a bad frame without losing the stream.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "clutterseg/parallel.hpp"
#include "clutterseg/pipeline.hpp"
#include "clutterseg/synth/dataset.hpp"

using namespace clutterseg;

namespace {

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

}  // namespace

TEST(Threads, EveryRowOnceForAnyThreadCountAndConcurrentCallers) {
  for (int threads : {0, 1, 2, 4}) {
    std::vector<std::thread> callers;
    std::atomic<int> wrong{0};
    for (int c = 0; c < 3; ++c)
      callers.emplace_back([&, threads] {
        set_threads(threads);
        for (int rep = 0; rep < 50; ++rep) {
          const int rows = 1 + 37 * rep % 500;
          std::vector<std::atomic<int>> hits(static_cast<size_t>(rows));
          parallel_for_rows(rows, [&](int begin, int end) {
            for (int y = begin; y < end; ++y) hits[static_cast<size_t>(y)]++;
          });
          for (auto& h : hits) wrong += h.load() != 1;
        }
      });
    for (auto& t : callers) t.join();
    EXPECT_EQ(wrong.load(), 0) << "threads " << threads;
  }
  set_threads(0);
  EXPECT_GE(region_threads(), 1);
  set_threads(1);
  EXPECT_EQ(region_threads(), 1);
}

TEST(Threads, AnExceptionInARowReachesTheCallerAndThePoolStaysUsable) {
  set_threads(2);
  EXPECT_THROW(parallel_for_rows(400, [](int begin, int) {
                 if (begin == 384) throw Error("row failed");
               }),
               Error);
  std::atomic<int> rows{0};
  parallel_for_rows(400, [&](int begin, int end) { rows += end - begin; });
  EXPECT_EQ(rows.load(), 400);
  set_threads(0);
}

TEST(Threads, PipelineGivesSegmentersResultsInOrderAndSurvivesABadFrame) {
  // A moving object over a static table at 320x240 (cheap), so that the temporal window matters.
  const Camera camera = synth::default_camera(320, 240);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 7; ++i) frames.push_back(synth::synthesize("sequence", 3, i, camera, synth::Sensor::KinectV1).sensor.depth);
  const cv::Mat bad(240, 320, CV_32F, cv::Scalar(0));  // no measurement: an Error, outside the window
  const int bad_at = 3;

  Params params;
  Segmenter segmenter(params);
  std::vector<Result> expected;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (static_cast<int>(i) == bad_at) EXPECT_THROW(segmenter.segment(bad, camera), Error);
    expected.push_back(segmenter.segment(frames[i], camera));
  }

  for (int workers : {1, 2, 3}) {
    params.threads = workers;
    Pipeline pipeline(params);
    EXPECT_EQ(pipeline.workers(), workers);
    std::vector<Result> got;
    int errors = 0;
    auto take = [&] {
      try {
        got.push_back(pipeline.pop());
      } catch (const Error&) {
        ++errors;
        EXPECT_EQ(got.size(), static_cast<size_t>(bad_at)) << "the error comes in the bad frame's place";
      }
    };
    for (size_t i = 0; i < frames.size(); ++i) {
      if (static_cast<int>(i) == bad_at) {
        if (pipeline.in_flight() >= pipeline.capacity()) take();
        pipeline.push(bad, camera);
      }
      if (pipeline.in_flight() >= pipeline.capacity()) take();
      pipeline.push(frames[i], camera);
    }
    while (pipeline.in_flight() > 0) take();
    EXPECT_EQ(errors, 1);
    ASSERT_EQ(got.size(), expected.size());
    for (size_t i = 0; i < got.size(); ++i) {
      EXPECT_TRUE(same(got[i].object_labels, expected[i].object_labels)) << "workers " << workers << ", frame " << i;
      EXPECT_TRUE(same(got[i].depth, expected[i].depth)) << "workers " << workers << ", frame " << i;
      EXPECT_EQ(got[i].objects.size(), expected[i].objects.size());
      ASSERT_FALSE(got[i].timings_ms.empty());
      EXPECT_EQ(got[i].timings_ms.back().first, "total");
    }
  }
  EXPECT_THROW(Pipeline(params).pop(), Error);  // nothing in flight
}
