// Threads (issue 19): the row pool covers every row once, also with concurrent callers; the cross-frame
// Pipeline gives Segmenter's results byte for byte, in order, with the temporal window carried across
// frames, and reports a bad frame without losing the stream.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "clutterseg/io.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/pipeline.hpp"

using namespace clutterseg;

namespace {

namespace fs = std::filesystem;

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::countNonZero(a != b) == 0;
}

// Real frames of a dev set at 320x240 (cheap: these tests also run under ASan and TSan), with the camera
// that sees them at that size.
struct HalfSizeFrames {
  Camera camera;
  std::vector<cv::Mat> depth;
};

HalfSizeFrames half_size_frames(const std::string& set, const std::vector<std::string>& names) {
  const fs::path dir = fs::path(CLUTTERSEG_DATA_DIR) / set;
  HalfSizeFrames frames{read_camera_json(dir / "camera.json"), {}};
  for (const std::string& name : names) {
    cv::Mat depth = read_depth_png(dir / "depth" / (name + ".png"));
    cv::resize(depth, depth, {frames.camera.width / 2, frames.camera.height / 2}, 0, 0, cv::INTER_NEAREST);
    frames.depth.push_back(depth);
  }
  Camera& c = frames.camera;
  c.fx /= 2, c.fy /= 2, c.cx = (c.cx - 0.5) / 2, c.cy = (c.cy - 0.5) / 2;
  c.width /= 2, c.height /= 2;
  return frames;
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
  // Consecutive frames of a real video (YCB-Video 0000, moving camera), so that the temporal window matters.
  const HalfSizeFrames video =
      half_size_frames("ycbv-0000", {"000001", "000002", "000003", "000004", "000005", "000006", "000007"});
  const Camera& camera = video.camera;
  const std::vector<cv::Mat>& frames = video.depth;
  const cv::Mat bad(camera.height, camera.width, CV_32F, cv::Scalar(0));  // no measurement: an Error
  const int bad_at = 3;

  Params params;
  Segmenter segmenter(params);
  std::vector<Result> expected;
  for (size_t i = 0; i < frames.size(); ++i) {
    if (static_cast<int>(i) == bad_at) EXPECT_THROW(segmenter.segment(bad, camera), Error);
    expected.push_back(segmenter.segment(frames[i], camera));
  }
  int carried = 0;  // frames whose smoothed depth differs from the frame's alone: the window is in play
  for (size_t i = 1; i < frames.size(); ++i)
    carried += !same(Segmenter(params).segment(frames[i], camera).depth, expected[i].depth);
  ASSERT_GT(carried, 0);

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

// Several Segmenters in threads at once give each the result it gives alone (no shared state); also run
// under ThreadSanitizer by scripts/sanitize.sh.
TEST(Threads, SegmentersInThreadsAtOnceGiveTheirSingleThreadedResults) {
  const HalfSizeFrames scenes = half_size_frames("osd-kinect", {"test42", "test50", "test63"});
  const Camera& small = scenes.camera;
  const std::vector<cv::Mat>& frames = scenes.depth;
  Params params;
  params.threads = 1;
  // Each thread streams the frames in its own order through its own Segmenter (temporal window on).
  const auto stream = [&](int offset) {
    Segmenter s(params);
    std::vector<cv::Mat> labels;
    for (size_t k = 0; k < 2 * frames.size(); ++k)
      labels.push_back(s.segment(frames[(k + static_cast<size_t>(offset)) % frames.size()], small).object_labels.clone());
    return labels;
  };
  std::vector<std::vector<cv::Mat>> alone(3), together(3);
  for (int t = 0; t < 3; ++t) alone[static_cast<size_t>(t)] = stream(t);
  std::vector<std::thread> threads;
  for (int t = 0; t < 3; ++t) threads.emplace_back([&, t] { together[static_cast<size_t>(t)] = stream(t); });
  for (auto& th : threads) th.join();
  for (size_t t = 0; t < 3; ++t)
    for (size_t k = 0; k < alone[t].size(); ++k)
      EXPECT_EQ(cv::countNonZero(alone[t][k] != together[t][k]), 0) << "thread " << t << " frame " << k;
}
