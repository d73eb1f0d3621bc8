// Every input that once crashed, aborted or hung clutterseg (tests/data/bad-inputs, found by fuzzing;
// docs/RELIABILITY.md) gets a one-line error naming the file and the problem, a non-zero exit and no
// output, or a correct result; within seconds (each run is under `timeout`, so a hang fails the test).
// Plus the checks behind them: parameter ranges, intrinsics and frame size bounds, exceptions inside
// parallel loops, and the eval matching bounded by the pixels.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <stdexcept>

#include "cli.hpp"
#include "clutterseg/config.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/limits.hpp"
#include "clutterseg/metrics.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/segmenter.hpp"
#ifdef CLUTTERSEG_WITH_PCL
#include "clutterseg/pcl/pcd.hpp"
#endif

using namespace clutterseg;
using namespace clutterseg::testing_cli;

namespace {
const fs::path kBad = fs::path(CLUTTERSEG_SOURCE_DIR) / "tests" / "data" / "bad-inputs";
const fs::path kData = CLUTTERSEG_DATA_DIR;

// `clutterseg ARGS` under a 30 s timeout (exit 124 when it runs out).
CliRun run_bounded(const std::string& args, const fs::path& tmp) { return run_cli(args, tmp, "timeout 30 "); }

// The one-line-error contract: non-zero exit (not a crash or timeout), one line naming `names` and
// containing `problem`, nothing written to `out`.
void expect_refused(const CliRun& r, const std::string& names, const std::string& problem, const fs::path& out,
                    const std::string& what) {
  EXPECT_EQ(r.code, 1) << what << ": " << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << what << ": " << r.err;
  EXPECT_NE(r.err.find(names), std::string::npos) << what << ": " << r.err;
  EXPECT_NE(r.err.find(problem), std::string::npos) << what << ": " << r.err;
  EXPECT_FALSE(fs::exists(out) && !fs::is_empty(out)) << what << ": wrote output";
}

}  // namespace

TEST(Reliability, FuzzedPcdFilesAreRefusedBeforePclReadsThem) {
  const fs::path tmp = fresh_dir("rel-pcd");
  const std::vector<fs::path> named = {kBad / "pcd-fuzzed.pcd", kBad / "pcd-compressed-zero-size.pcd", kBad / "pcd-min.pcd",
                                       kBad / "pcd-lzf-damaged.pcd", kBad / "pcd-viewpoint-not-a-number.pcd",
                                       kBad / "pcd-body-like-a-header.pcd", kBad / "pcd-header-vertical-tab.pcd",
                                       kBad / "pcd-comment-then-header.pcd", kBad / "pcd-header-tab-lines.pcd"};
  for (const fs::path& f : named) {
    const fs::path out = tmp / "out";
    const auto r = run_bounded("segment " + f.string() + " --fx 525 --out " + out.string(), tmp);
    expect_refused(r, f.string() + ": ", "not a PCD file", out, f.filename().string());
  }
#ifdef CLUTTERSEG_WITH_PCL
  // The other 17 in-process (a crash would end the test binary).
  int refused = 0;
  for (const auto& e : fs::directory_iterator(kBad / "pcd-fuzzed-more")) {
    const std::string message = error_of([&] { read_organized_pcd(e.path()); });
    EXPECT_NE(message.find(e.path().string() + ": not a PCD file"), std::string::npos) << message;
    EXPECT_EQ(message.find('\n'), std::string::npos);
    ++refused;
  }
  EXPECT_GE(refused, 17);
  // Found by fuzz_pcd: points 4e16 px off their pixels (the message's int conversion overflowed).
  const fs::path far = kBad / "pcd-not-a-projection-huge.pcd";
  EXPECT_NE(error_of([&] { read_organized_pcd(far); }).find("1000000 or more px"), std::string::npos);
#endif
}

TEST(Reliability, DepthFilesAreReadAsPngOnly) {
  const fs::path tmp = fresh_dir("rel-png");
  for (const char* name : {"depth-png-slow.png", "depth-png-slow-2.png", "depth-png-slow-3.png"}) {
    const fs::path out = tmp / "out";
    const auto r = run_bounded("segment " + (kBad / name).string() + " --fx 525 --out " + out.string(), tmp);
    expect_refused(r, (kBad / name).string() + ": ", "PNG", out, name);
  }
  // Another format under a .png name, and a PNG under another name, are refused too.
  cv::imwrite((tmp / "depth.tiff").string(), cv::Mat(48, 64, CV_16U, cv::Scalar(900)));
  fs::copy_file(tmp / "depth.tiff", tmp / "tiff-inside.png");
  const auto r1 = run_bounded("segment " + (tmp / "tiff-inside.png").string() + " --fx 60 --out " + (tmp / "o1").string(), tmp);
  expect_refused(r1, "tiff-inside.png: ", "not a PNG file", tmp / "o1", "tiff named .png");
  const auto r2 = run_bounded("segment " + (tmp / "depth.tiff").string() + " --fx 60 --out " + (tmp / "o2").string(), tmp);
  expect_refused(r2, "depth.tiff: ", "not a .png file", tmp / "o2", "tiff");
}

TEST(Reliability, CameraJsonWithNumbersBeyondTheirTypeIsRefused) {
  const fs::path tmp = fresh_dir("rel-camera");
  const fs::path depth = kBad / "depth-64x48.png";
  const std::vector<std::pair<const char*, const char*>> cases = {
      {"camera-json-fuzzed.json", "'width'"},
      {"camera-width-huge-float.json", "'width'"},
      {"camera-unit-1e300.json", "depth_unit_m"},
  };
  for (const auto& [name, problem] : cases) {
    const auto r = run_bounded("segment " + depth.string() + " --camera " + (kBad / name).string() + " --out " +
                                   (tmp / "out").string(), tmp);
    expect_refused(r, (kBad / name).string(), problem, tmp / "out", name);
  }
  // As a dataset's camera.json: the same message.
  fs::create_directories(tmp / "set" / "depth");
  fs::copy_file(depth, tmp / "set" / "depth" / "000000.png");
  fs::copy_file(kBad / "camera-width-huge-float.json", tmp / "set" / "camera.json");
  const auto r = run_bounded("segment " + (tmp / "set").string() + " --out " + (tmp / "out").string(), tmp);
  expect_refused(r, "camera.json", "'width'", tmp / "out", "dataset camera.json");
}

TEST(Reliability, FocalLengthsBeyondAOneDegreeFieldOfViewAreRefused) {
  const fs::path tmp = fresh_dir("rel-fx");
  const fs::path depth = kBad / "depth-64x48.png";
  for (const char* fx : {"1e9", "1e10"}) {
    const auto r = run_bounded("segment " + depth.string() + " --fx " + fx + " --cx 32 --cy 24 --out " +
                                   (tmp / "out").string(), tmp);
    expect_refused(r, "depth-64x48.png: ", "focal length", tmp / "out", fx);
  }
  for (double fx : {1e6, 1e7, 1e300, std::numeric_limits<double>::infinity(), std::nan(""), -5.0, 0.0, 0.001}) {
    const Camera c{fx, 60, 32, 24, 64, 48};
    EXPECT_NE(error_of([&] { check_camera(c, 64, 48, "cam"); }).find("focal length"), std::string::npos) << fx;
  }
  // camera-fx-1e8.json with a 640x480 frame.
  const auto r = run_bounded("segment " + (kData / "osd-kinect" / "depth" / "test50.png").string() + " --camera " +
                                 (kBad / "camera-fx-1e8.json").string() + " --out " + (tmp / "out").string(), tmp);
  expect_refused(r, "test50.png: ", "field of view below 1 degree", tmp / "out", "fx 1e8");
  // The largest focal length taken (a 1.1 degree view) gives a result: pixel sizes are capped.
  const auto ok = run_bounded("segment " + depth.string() + " --fx 2700 --cx 32 --cy 24 --out " + (tmp / "ok").string(), tmp);
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_TRUE(fs::exists(tmp / "ok" / "depth-64x48.json"));
}

TEST(Reliability, PixelScaleIsCappedWhateverTheFocalLength) {
  for (double f : {1e3, 1e6, 1e10, 1e300, std::numeric_limits<double>::infinity(), std::nan("")}) {
    const PixelScale px(f, f);
    EXPECT_LE(px.factor, PixelScale::kMax);
    EXPECT_LE(px.length(50), 50 * PixelScale::kMax + 1);
    EXPECT_LE(px.area(100000), 100000 * PixelScale::kMax * PixelScale::kMax + 1);
    EXPECT_LE(px.odd(31), 31 * PixelScale::kMax + 1);
  }
}

// Per-patch statistics read a bounded sample: VGA's budget in any larger frame, a share of it in a smaller
// one (a quarter at 320x240, never less), and never zero.
TEST(Reliability, PerPatchSamplesAreBoundedWhateverTheFrameSize) {
  EXPECT_EQ(sample_budget(2000, 640 * 480), 2000u);
  EXPECT_EQ(sample_budget(2000, 320 * 240), 500u);
  EXPECT_EQ(sample_budget(2000, 64 * 48), 500u);
  EXPECT_EQ(sample_budget(2000, 4096 * 4096), 2000u);
  EXPECT_EQ(sample_budget(2000, 480 * 360), 1125u);
  EXPECT_EQ(sample_budget(1, 320 * 240), 1u);
}

TEST(Reliability, ConfigValuesAreTypeAndRangeCheckedNamingTheKey) {
  const fs::path tmp = fresh_dir("rel-config");
  const fs::path depth = kBad / "depth-64x48.png";
  const auto segment = [&](const fs::path& config) {
    return run_bounded("segment " + depth.string() + " --fx 60 --config " + config.string() + " --out " +
                           (tmp / "out").string(), tmp);
  };
  const std::vector<std::pair<const char*, const char*>> files = {
      {"config-fuzzed.json", "smoothing.temporal_frames"},
      {"config-int-from-huge-float.json", "smoothing.temporal_frames"},
      {"config-histogram-bins-0.json", "patches.histogram_bins"},
  };
  for (const auto& [name, key] : files) expect_refused(segment(kBad / name), (kBad / name).string(), key, tmp / "out", name);
  const std::vector<std::pair<std::string, std::string>> inline_cases = {
      {R"({"threads": 1.5})", "threads"},
      {R"({"threads": 10000})", "threads"},
      {R"({"seed": -1})", "seed"},
      {R"({"normals": {"smooth_ksize": 100001}})", "normals.smooth_ksize"},
      {R"({"normals": {"smooth_ksize": 4}})", "normals.smooth_ksize"},
      {R"({"graph": {"theta_c": -1}})", "graph.theta_c"},
      {R"({"graph": {"theta_c": "high"}})", "graph.theta_c"},
      {R"({"graph": 3})", "graph"},
      {R"({"support": {"enabled": 1}})", "support.enabled"},
      {R"({"patches": {"min_size_px": 99999999999}})", "patches.min_size_px"},
  };
  for (const auto& [text, key] : inline_cases) {
    const std::string message = error_of([&text = text] { params_from_json(text, "cfg.json"); });
    EXPECT_EQ(message.rfind("cfg.json: parameter '" + key + "' = ", 0), 0u) << text << ": " << message;
  }
  const fs::path file = tmp / "config.json";
  { std::ofstream(file) << inline_cases[0].first; }
  expect_refused(segment(file), file.string() + ": parameter 'threads' = 1.5", "integer", tmp / "out", "threads 1.5");
}

TEST(Reliability, CommandLineParametersAreRangeChecked) {
  const fs::path tmp = fresh_dir("rel-flags");
  const fs::path depth = kBad / "depth-64x48.png";
  for (const std::string flag : {"--theta-c -1", "--theta-c nan", "--theta-h 2", "--threads 10000"}) {
    const auto r = run_bounded("segment " + depth.string() + " --fx 60 " + flag + " --out " + (tmp / "out").string(), tmp);
    EXPECT_NE(r.code, 0) << flag;
    EXPECT_EQ(count_lines(r.err), 1) << flag << ": " << r.err;
    EXPECT_FALSE(fs::exists(tmp / "out")) << flag;
  }
  const auto r = run_bounded("segment " + depth.string() + " --fx 60 --theta-c -1 --out " + (tmp / "out").string(), tmp);
  EXPECT_NE(r.err.find("parameter 'graph.theta_c' = -1"), std::string::npos) << r.err;
}

TEST(Reliability, EveryParameterHasARangeTheDefaultsMeet) {
  EXPECT_NO_THROW(validate(Params{}));
  EXPECT_NO_THROW(params_from_json(params_to_json(Params{}), "defaults"));
  Params p;
  p.patches.histogram_bins = 0;
  EXPECT_NE(error_of([&] { Segmenter s(p); }).find("parameter 'patches.histogram_bins' = 0"), std::string::npos);
  p = Params{};
  p.graph.theta_c = std::nan("");
  EXPECT_NE(error_of([&] { Segmenter s(p); }).find("graph.theta_c"), std::string::npos);
  p = Params{};
  p.normals.smooth_ksize = 100001;
  EXPECT_NE(error_of([&] { segment(cv::Mat(48, 64, CV_32F, cv::Scalar(1.f)), Camera{}, p); }).find("normals.smooth_ksize"),
            std::string::npos);
}

TEST(Reliability, EvalOfAPredictionWithManyIdsIsBoundedByThePixels) {
  const fs::path tmp = fresh_dir("rel-eval");
  const fs::path set = kBad / "eval-many-ids";
  const auto r = run_bounded("eval " + set.string() + " --pred " + (set / "pred").string() + " --out " + (tmp / "out").string(), tmp);
  ASSERT_EQ(r.code, 0) << r.err;
  const auto summary = nlohmann::json::parse(slurp(tmp / "out" / "summary.json"));
  EXPECT_FALSE(summary.empty());
}

TEST(Reliability, MatchingOfAChainOfOverlapsIsExactOrBoundedAndAgreesWithTheDenseTable) {
  // Staggered stripes: ground-truth object i overlaps predicted objects i and i + 1, one connected
  // component with as many ids as a row has pixel pairs.
  const int w = 1024, h = 64;
  cv::Mat gt(h, w, CV_32S), pred(h, w, CV_32S);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      gt.at<int>(y, x) = 1 + (y * w + x) / 2;
      pred.at<int>(y, x) = 1 + (y * w + x + 1) / 2;
    }
  const FrameScores s = score_frame(gt, pred);
  EXPECT_EQ(s.gt_objects, w * h / 2);
  EXPECT_GT(s.matched, 0);
  EXPECT_GT(s.overlap_f, 0.4);

  // On small random frames, the sparse matching gives the dense Hungarian's total F.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 30; ++trial) {
    cv::Mat g(12, 12, CV_32S), q(12, 12, CV_32S);
    for (int y = 0; y < 12; ++y)
      for (int x = 0; x < 12; ++x) {
        g.at<int>(y, x) = static_cast<int>(rng() % 5);
        q.at<int>(y, x) = static_cast<int>(rng() % 6);
      }
    const FrameScores sparse = score_frame(g, q);
    std::vector<int> gi, qi;
    for (int v = 1; v < 5; ++v) if (cv::countNonZero(g == v)) gi.push_back(v);
    for (int v = 1; v < 6; ++v) if (cv::countNonZero(q == v)) qi.push_back(v);
    std::vector<std::vector<double>> f(gi.size(), std::vector<double>(qi.size()));
    for (size_t a = 0; a < gi.size(); ++a)
      for (size_t b = 0; b < qi.size(); ++b) {
        const double inter = cv::countNonZero((g == gi[a]) & (q == qi[b]));
        f[a][b] = 2 * inter / (cv::countNonZero(g == gi[a]) + cv::countNonZero(q == qi[b]));
      }
    const std::vector<int> dense = max_weight_assignment(f);
    double best = 0, got = 0;
    for (size_t a = 0; a < gi.size(); ++a) if (dense[a] >= 0) best += f[a][static_cast<size_t>(dense[a])];
    for (const auto& [gid, qid] : sparse.matches) {
      const size_t a = static_cast<size_t>(std::find(gi.begin(), gi.end(), gid) - gi.begin());
      const size_t b = static_cast<size_t>(std::find(qi.begin(), qi.end(), qid) - qi.begin());
      got += f[a][b];
    }
    EXPECT_NEAR(got, best, 1e-9) << trial;
  }
}

TEST(Reliability, BadFrameOfAFolderRunIsSkippedWhateverItsException) {
  const fs::path tmp = fresh_dir("rel-folder");
  fs::create_directories(tmp / "set" / "depth");
  fs::copy_file(kData / "osd-kinect" / "camera.json", tmp / "set" / "camera.json");
  fs::copy_file(kData / "osd-kinect" / "depth" / "test50.png", tmp / "set" / "depth" / "a.png");
  fs::copy_file(kBad / "png-declared-1e6x1e6.png", tmp / "set" / "depth" / "b.png");
  fs::copy_file(kData / "osd-kinect" / "depth" / "test42.png", tmp / "set" / "depth" / "c.png");
  const auto r = run_bounded("segment " + (tmp / "set").string() + " --out " + (tmp / "out").string(), tmp);
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("b.png: 1000000x1000000 is beyond the largest frame"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(tmp / "out" / "a.json"));
  EXPECT_TRUE(fs::exists(tmp / "out" / "c.json"));
  EXPECT_FALSE(fs::exists(tmp / "out" / "b.json"));

  // An output folder that is a file: every frame fails with a message (a filesystem error), none crashes.
  { std::ofstream(tmp / "file") << "x"; }
  const auto f = run_bounded("segment " + (tmp / "set").string() + " --out " + (tmp / "file").string(), tmp);
  EXPECT_EQ(f.code, 1) << f.err;
  EXPECT_EQ(count_lines(f.err), 3) << f.err;
  EXPECT_EQ(f.err.find("internal error"), std::string::npos) << f.err;
}

TEST(Reliability, FramesBeyondTheSizeLimitAreRefusedBeforeTheyAreDecoded) {
  const fs::path tmp = fresh_dir("rel-huge");
  // 8000x6000 of constant depth: a 100 KB PNG that would take 4 GB and 50 s to segment.
  const fs::path huge = tmp / "huge.png";
  cv::imwrite(huge.string(), cv::Mat(6000, 8000, CV_16U, cv::Scalar(1000)), {cv::IMWRITE_PNG_COMPRESSION, 1});
  const auto r = run_bounded("segment " + huge.string() + " --fx 5000 --out " + (tmp / "out").string(), tmp);
  expect_refused(r, "huge.png: 8000x6000", "beyond the largest frame", tmp / "out", "8000x6000");
  // The library refuses it as well (Python, ROS).
  EXPECT_NE(error_of([] {
              Camera c{5000, 5000, 4000, 3000, 8000, 6000};
              segment(cv::Mat(6000, 8000, CV_16U, cv::Scalar(1000)), c);
            }).find("beyond the largest frame"),
            std::string::npos);
  EXPECT_NO_THROW(check_frame_size(3840, 2160, "4k"));
}

TEST(Reliability, DepthUnitsThatMakeEveryDepthInfiniteAreRefused) {
  Camera c{60, 60, 32, 24, 64, 48, 1e300};
  EXPECT_NE(error_of([&] { segment(cv::Mat(48, 64, CV_16U, cv::Scalar(1000)), c); }).find("depth_unit_m"), std::string::npos);
  c.depth_unit_m = 0.001;
  cv::Mat inf(48, 64, CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  EXPECT_NE(error_of([&] { segment(inf, c); }).find("no valid measurement"), std::string::npos);
}

TEST(Reliability, AnExceptionInsideAParallelLoopReachesTheCaller) {
  for (int threads : {1, 2}) {
    set_threads(threads);
    EXPECT_THROW(parallel_for_rows(256, [](int begin, int) {
                   if (begin >= 128) throw std::runtime_error("row failed");
                 }),
                 std::runtime_error);
  }
  set_threads(0);
}

TEST(Reliability, NoiseFramesEndWithinTheirBounds) {
  // Adversarial depth: independent noise makes a patch of nearly every pixel group, the worst case for
  // the graph cut, region growing and RANSAC loops; it must end (ctest's timeout) with a result.
  std::mt19937 rng(3);
  cv::Mat depth(240, 320, CV_16U);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) depth.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(500 + rng() % 1500);
  Camera c{262.5, 262.5, 159.5, 119.5, 320, 240};
  const Result r = segment(depth, c);
  EXPECT_EQ(r.object_labels.size(), depth.size());
  cv::Mat blocks(240, 320, CV_16U);
  for (int y = 0; y < blocks.rows; ++y)
    for (int x = 0; x < blocks.cols; ++x)
      blocks.at<std::uint16_t>(y, x) = static_cast<std::uint16_t>(600 + 40 * (((x / 8) * 7 + (y / 8) * 13) % 11));
  EXPECT_EQ(segment(blocks, c).object_labels.size(), blocks.size());
}
