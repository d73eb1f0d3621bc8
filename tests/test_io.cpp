// Readers on the real files in ../shared/data/dev, and clear errors for files that are not depth.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "cli.hpp"
#include "clutterseg/config.hpp"
#include "clutterseg/io.hpp"

using namespace clutterseg;
using namespace clutterseg::testing_cli;

namespace {
const fs::path kData = CLUTTERSEG_DATA_DIR;

}  // namespace

TEST(Io, ReadsEveryDevDataset) {
  for (const char* set : {"osd-kinect", "tabletop-realsense", "ycbv-0000", "ycbv-0003"}) {
    const Camera cam = read_camera_json(kData / set / "camera.json");
    const auto frames = list_dataset(kData / set);
    ASSERT_FALSE(frames.empty()) << set;
    for (size_t i = 1; i < frames.size(); ++i) EXPECT_LT(frames[i - 1].name, frames[i].name);  // time order
    const cv::Mat d = read_depth_png(frames[0].depth);
    EXPECT_EQ(d.type(), CV_16UC1);
    EXPECT_EQ(d.cols, cam.width);
    EXPECT_EQ(d.rows, cam.height);
    EXPECT_GT(cv::countNonZero(d), d.total() / 3) << set;
    EXPECT_TRUE(frames[0].color.has_value()) << set;
  }
  const auto ycbv = list_dataset(kData / "ycbv-0000");
  ASSERT_TRUE(ycbv[0].label.has_value());
  const cv::Mat labels = read_label_png(*ycbv[0].label);
  double max_id = 0;
  cv::minMaxLoc(labels, nullptr, &max_id);
  EXPECT_GT(max_id, 0);
}

TEST(Io, ErrorsNameTheFileAndTheProblem) {
  const fs::path tmp = fresh_dir("io");
  const fs::path colour = kData / "osd-kinect" / "color" / "test50.png";
  EXPECT_NE(error_of([&] { read_depth_png(colour); }).find("test50.png: is a 8-bit 3-channel image"), std::string::npos);
  EXPECT_NE(error_of([&] { read_depth_png(tmp / "missing.png"); }).find("missing.png: no such file"), std::string::npos);
  cv::imwrite((tmp / "gray8.png").string(), cv::Mat(4, 4, CV_8U, cv::Scalar(3)));
  EXPECT_NE(error_of([&] { read_depth_png(tmp / "gray8.png"); }).find("gray8.png: is a 8-bit 1-channel image"), std::string::npos);
  { std::ofstream(tmp / "bad.json") << "{\"fx\": 1"; }
  EXPECT_NE(error_of([&] { read_camera_json(tmp / "bad.json"); }).find("bad.json: is not valid JSON"), std::string::npos);
  { std::ofstream(tmp / "partial.json") << "{\"fx\": 1, \"fy\": 1}"; }
  EXPECT_NE(error_of([&] { read_camera_json(tmp / "partial.json"); }).find("partial.json: needs numbers"), std::string::npos);
  EXPECT_NE(error_of([&] { list_dataset(tmp); }).find("is not a dataset folder"), std::string::npos);
}

TEST(Io, AtomicWriteLeavesNothingOnFailure) {
  const fs::path tmp = fresh_dir("atomic");
  fs::create_directories(tmp / "is-a-dir.png");  // cannot be replaced by a file
  EXPECT_THROW(write_png_atomic(tmp / "is-a-dir.png", cv::Mat(2, 2, CV_16U, cv::Scalar(1))), std::exception);
  for (const auto& e : fs::directory_iterator(tmp)) EXPECT_EQ(e.path().string().find(".partial"), std::string::npos);
}

TEST(Config, RoundTripsAndRejectsUnknownKeys) {
  Params p;
  p.graph.theta_c = 0.7;
  p.edges.theta = 0.8;
  const Params q = params_from_json(params_to_json(p), "test");
  EXPECT_DOUBLE_EQ(q.graph.theta_c, 0.7);
  EXPECT_DOUBLE_EQ(q.edges.theta, 0.8);
  EXPECT_EQ(params_from_json("{\"edges\": {\"theta\": 0.5}}", "x").adjacency.d_max, Params{}.adjacency.d_max);
  EXPECT_NE(error_of([] { params_from_json("{\"edges\": {\"thetta\": 0.5}}", "cfg.json"); }).find("cfg.json: unknown parameter 'edges.thetta'"),
            std::string::npos);
}
