// `clutterseg segment` end to end: the files a user gets, and one-line errors for bad input with a
// non-zero exit and nothing written for the bad frame.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli.hpp"
#include "clutterseg/io.hpp"

using namespace clutterseg;
using namespace clutterseg::testing_cli;

namespace {
const fs::path kData = CLUTTERSEG_DATA_DIR;

// A dataset folder with two real osd-kinect frames, plus whatever the test adds.
fs::path small_dataset(const fs::path& root) {
  fs::create_directories(root / "depth");
  fs::copy_file(kData / "osd-kinect" / "camera.json", root / "camera.json");
  for (const char* n : {"test42", "test50"})
    fs::copy_file(kData / "osd-kinect" / "depth" / (std::string(n) + ".png"), root / "depth" / (std::string(n) + ".png"));
  return root;
}
}  // namespace

TEST(SegmentCli, WritesPatchesDebugImagesAndJson) {
  const fs::path tmp = fresh_dir("seg-ok");
  const auto r = run_cli("segment " + (kData / "osd-kinect").string() + " --out " + (tmp / "out").string(), tmp);
  ASSERT_EQ(r.code, 0) << r.err;
  for (const char* n : {"learn6", "test42", "test50", "test63", "test64"}) {
    const cv::Mat patch = cv::imread((tmp / "out" / "patch" / (std::string(n) + ".png")).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(patch.type(), CV_16UC1) << n;
    double max_id = 0;
    cv::minMaxLoc(patch, nullptr, &max_id);
    EXPECT_GE(max_id, 3) << n;  // at least table, wall and one object face
    for (const char* img : {"normals.png", "edges.png", "patches.png"})
      EXPECT_TRUE(fs::exists(tmp / "out" / "debug" / n / img)) << n << " " << img;
    const auto j = nlohmann::json::parse(slurp(tmp / "out" / (std::string(n) + ".json")));
    ASSERT_TRUE(j["timings_ms"].contains("total"));
    double stages = 0;
    for (const auto& [k, v] : j["timings_ms"].items())
      if (k != "total") stages += v.get<double>();
    EXPECT_LE(stages, j["timings_ms"]["total"].get<double>() + 1e-6);
  }
}

TEST(SegmentCli, BadInputsGiveOneLineErrors) {
  const fs::path tmp = fresh_dir("seg-bad");
  const std::string cam = " --camera " + (kData / "osd-kinect" / "camera.json").string();
  struct Case {
    std::string input, extra, expected;
  };
  cv::imwrite((tmp / "eight.png").string(), cv::Mat(480, 640, CV_8U, cv::Scalar(9)));
  cv::imwrite((tmp / "empty.png").string(), cv::Mat(480, 640, CV_16U, cv::Scalar(0)));
  cv::imwrite((tmp / "small.png").string(), cv::Mat(240, 320, CV_16U, cv::Scalar(900)));
  const std::vector<Case> cases = {
      {(tmp / "missing.png").string(), cam, "missing.png: no such file"},
      {(tmp / "eight.png").string(), cam, "eight.png: is a 8-bit 1-channel image"},
      {(kData / "osd-kinect" / "color" / "test50.png").string(), cam, "test50.png: is a 8-bit 3-channel image"},
      {(tmp / "empty.png").string(), cam, "empty.png: depth image has no valid measurement"},
      {(tmp / "small.png").string(), cam, "small.png: intrinsics are for 640x480 but the image is 320x240"},
      {(tmp / "small.png").string(), "", "small.png: no intrinsics"},
  };
  for (const auto& c : cases) {
    const fs::path out = tmp / "out";
    fs::remove_all(out);
    const auto r = run_cli("segment " + c.input + c.extra + " --out " + out.string(), tmp);
    EXPECT_NE(r.code, 0) << c.input;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(c.expected), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out) && !fs::is_empty(out)) << "wrote output for " << c.input;
  }
}

TEST(SegmentCli, BadFrameInAFolderIsSkippedAndDoesNotPoisonTheWindow) {
  const fs::path tmp = fresh_dir("seg-folder");
  const fs::path set = small_dataset(tmp / "set");
  // "test45" sorts between the good frames; it is a colour image, not depth.
  fs::copy_file(kData / "osd-kinect" / "color" / "test50.png", set / "depth" / "test45.png");
  const auto r = run_cli("segment " + set.string() + " --out " + (tmp / "out").string(), tmp);
  EXPECT_EQ(r.code, 1);
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("test45.png"), std::string::npos);
  EXPECT_TRUE(fs::exists(tmp / "out" / "test42.json"));
  EXPECT_TRUE(fs::exists(tmp / "out" / "test50.json"));
  EXPECT_FALSE(fs::exists(tmp / "out" / "test45.json"));
  EXPECT_FALSE(fs::exists(tmp / "out" / "patch" / "test45.png"));
  // test50 after the bad frame gives the same patches as test50 after test42 alone.
  fs::remove(set / "depth" / "test45.png");
  const auto clean = run_cli("segment " + set.string() + " --out " + (tmp / "clean").string(), tmp);
  ASSERT_EQ(clean.code, 0);
  EXPECT_EQ(slurp(tmp / "out" / "patch" / "test50.png"), slurp(tmp / "clean" / "patch" / "test50.png"));
}

TEST(SegmentCli, DumpConfigIsValidJsonWithUnits) {
  const fs::path tmp = fresh_dir("seg-config");
  const auto r = run_cli("--dump-config", tmp);
  ASSERT_EQ(r.code, 0);
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_DOUBLE_EQ(j["graph"]["theta_c"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["adjacency"]["d_max"].get<double>(), 0.015);
}
