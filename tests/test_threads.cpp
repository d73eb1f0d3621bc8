// Several Segmenters in threads at once give each the result it gives alone (no shared state). Also run
// under ThreadSanitizer by scripts/sanitize.sh.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <thread>

#include "clutterseg/io.hpp"
#include "clutterseg/segmenter.hpp"

using namespace clutterseg;

TEST(Threads, SegmentersInThreadsAtOnceGiveTheirSingleThreadedResults) {
  const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "osd-kinect";
  const Camera camera = read_camera_json(set / "camera.json");
  std::vector<cv::Mat> frames;
  for (const char* name : {"test42", "test50", "test63"}) {
    cv::Mat depth = read_depth_png(set / "depth" / (std::string(name) + ".png"));
    cv::resize(depth, depth, {320, 240}, 0, 0, cv::INTER_NEAREST);  // small: the test also runs under TSan
    frames.push_back(depth);
  }
  Camera small = camera;
  small.fx /= 2, small.fy /= 2, small.cx = (small.cx - 0.5) / 2, small.cy = (small.cy - 0.5) / 2;
  small.width = 320, small.height = 240;
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
