// `clutterseg eval` end to end on tiny datasets written by the tests: numbers a user reads in the table,
// the CSV and summary.json, families, failing frames, sweeps, and clear errors.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "clutterseg/io.hpp"
#include "cli.hpp"
#include "scenes.hpp"

using namespace clutterseg;
using namespace clutterseg::testing_cli;
namespace fs = std::filesystem;

namespace {

void write_labels(const fs::path& p, const cv::Mat& labels) {
  fs::create_directories(p.parent_path());
  cv::Mat u16;
  labels.convertTo(u16, CV_16U);
  ASSERT_TRUE(cv::imwrite(p.string(), u16));
}

// A 20x20 dataset: flat depth, and ground truth / prediction pairs with hand-known scores.
//   a (family boxes):     perfect, ids differ        -> tp 1, Overlap F 1
//   b (family cylinders): one object split in two    -> tp 0.5, Overlap F 0.5
//   c (family boxes):     no prediction file         -> fails, the run goes on
fs::path tiny_dataset(const fs::path& root) {
  Camera cam;
  cam.fx = cam.fy = 20;
  cam.cx = cam.cy = 9.5;
  cam.width = cam.height = 20;
  fs::create_directories(root / "depth");
  write_camera_json(root / "camera.json", cam);
  const cv::Mat depth(20, 20, CV_16U, cv::Scalar(800));
  cv::Mat whole(20, 20, CV_32S, cv::Scalar(0)), halves = whole.clone();
  whole(cv::Rect(2, 4, 12, 6)).setTo(3);
  halves(cv::Rect(2, 4, 6, 6)).setTo(1);
  halves(cv::Rect(8, 4, 6, 6)).setTo(2);
  for (const char* name : {"a", "b", "c"}) {
    cv::imwrite((root / "depth" / (std::string(name) + ".png")).string(), depth);
    write_labels(root / "label" / (std::string(name) + ".png"), whole);
  }
  write_labels(root / "pred" / "a.png", whole * 5);
  write_labels(root / "pred" / "b.png", halves);
  std::ofstream(root / "scenes.json") << R"({"frames": [{"name": "a", "family": "boxes"},
      {"name": "b", "family": "cylinders"}, {"name": "c", "family": "boxes"}]})";
  return root;
}

const nlohmann::json& group(const nlohmann::json& run, const std::string& family) {
  for (const auto& g : run["groups"])
    if (g["family"] == family) return g;
  throw std::runtime_error("no group " + family);
}

}  // namespace

TEST(EvalCli, ScoresPredictionsPerFamilyAndReportsTheFailingFrame) {
  const fs::path tmp = fresh_dir("pred");
  const fs::path ds = tiny_dataset(tmp / "ds");
  const CliRun r = run_cli("eval " + ds.string() + " --pred " + (ds / "pred").string() + " --out " + (tmp / "o").string(), tmp);
  EXPECT_EQ(r.code, 1) << "a failed frame makes the exit code 1";
  EXPECT_NE(r.err.find("no prediction for frame c"), std::string::npos) << r.err;

  // The table: all frames, then one row per family (frames with scores, scenes = frames here).
  EXPECT_NE(r.out.find("| family | frames | scenes | tp | fp | fn | Overlap P"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| all | 2 | 2 | 75.0 ± 25.0 | 0.0 ± 0.0 | 25.0 ± 25.0 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| boxes | 1 | 1 | 100.0 | 0.0 | 0.0 | 100.0 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("| cylinders | 1 | 1 | 50.0 | 0.0 | 50.0 | 50.0 |"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 frame(s) failed"), std::string::npos);

  const auto summary = nlohmann::json::parse(slurp(tmp / "o" / "summary.json"));
  ASSERT_EQ(summary["runs"].size(), 1u);
  const auto& run = summary["runs"][0];
  EXPECT_DOUBLE_EQ(group(run, "all")["scores"]["overlap_f"]["mean"].get<double>(), 0.75);
  EXPECT_DOUBLE_EQ(group(run, "all")["scores"]["detected_75"]["mean"].get<double>(), 0.5);
  EXPECT_EQ(group(run, "boxes")["failed"], 1);
  EXPECT_EQ(run["failed_frames"][0]["frame"], "c");

  // One CSV row per frame, the failed one with its error and no scores.
  const std::string csv = slurp(tmp / "o" / "scenes.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 4);
  EXPECT_NE(csv.find(",cylinders,b,b,1,2,1,0.500000,0.000000,0.500000,0.500000,0.500000,0.500000,"), std::string::npos)
      << csv;
  EXPECT_NE(csv.find("no prediction for frame c"), std::string::npos);

  const std::string html = slurp(tmp / "o" / "report.html");
  EXPECT_NE(html.find("<table class=\"summary\""), std::string::npos);
  EXPECT_NE(html.find("id=\"frame-a\""), std::string::npos);
  EXPECT_NE(html.find("Failed frames"), std::string::npos);
  fs::remove_all(tmp);
}

TEST(EvalCli, WithoutMatplotlibTheReportSaysSoInOneLineAndHasEverythingElse) {
  const fs::path tmp = fresh_dir("noplots");
  const fs::path ds = tiny_dataset(tmp / "ds");
  fs::copy(ds / "pred" / "a.png", ds / "pred" / "c.png");
  const CliRun r = run_cli("eval " + ds.string() + " --pred " + (ds / "pred").string() + " --out " +
                               (tmp / "o").string(),
                           tmp, "CLUTTERSEG_PYTHON=/nonexistent/python3 ");
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("Plots are missing: no python3 with matplotlib"), std::string::npos) << r.err;
  const std::string html = slurp(tmp / "o" / "report.html");
  EXPECT_NE(html.find("<p class=\"note\" id=\"plot-note\">Plots are missing"), std::string::npos);
  EXPECT_EQ(html.find("id=\"plot-scatter\""), std::string::npos);
  EXPECT_NE(html.find("<table class=\"summary\""), std::string::npos);
  EXPECT_NE(html.find("id=\"frame-c\""), std::string::npos);
  fs::remove_all(tmp);
}

TEST(EvalCli, SizeMismatchedPredictionFailsThatFrameOnly) {
  const fs::path tmp = fresh_dir("size");
  const fs::path ds = tiny_dataset(tmp / "ds");
  write_labels(ds / "pred" / "c.png", cv::Mat(10, 20, CV_32S, cv::Scalar(1)));
  const CliRun r = run_cli("eval " + ds.string() + " --pred " + (ds / "pred").string(), tmp);
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.err.find("prediction: size 20x10 differs from the ground truth 20x20"), std::string::npos) << r.err;
  EXPECT_NE(r.out.find("| all | 2 |"), std::string::npos) << r.out;
  fs::remove_all(tmp);
}

TEST(EvalCli, SequenceCountsOneSceneAndSegmentOutputFolderIsAccepted) {
  const fs::path tmp = fresh_dir("seq");
  const fs::path ds = tiny_dataset(tmp / "ds");
  fs::remove(ds / "scenes.json");
  // `segment --out DIR` writes DIR/label/NAME.png: --pred DIR finds them there.
  fs::create_directories(tmp / "seg" / "label");
  for (const char* n : {"a", "b", "c"}) fs::copy(ds / "pred" / "a.png", tmp / "seg" / "label" / (std::string(n) + ".png"));
  const CliRun r = run_cli("eval " + ds.string() + " --sequence --pred " + (tmp / "seg").string(), tmp);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("| all | 3 | 1 | 100.0 |"), std::string::npos) << r.out;
  fs::remove_all(tmp);
}

TEST(EvalCli, ScenesJsonNamesScenesSoASequenceCountsOnce) {
  const fs::path tmp = fresh_dir("scenes");
  const fs::path ds = tiny_dataset(tmp / "ds");
  fs::copy(ds / "pred" / "b.png", ds / "pred" / "c.png");
  std::ofstream(ds / "scenes.json") << R"({"frames": [{"name": "a", "scene": "desk"}, {"name": "b", "scene": "desk"},
      {"name": "c", "scene": "shelf"}]})";
  const CliRun r = run_cli("eval " + ds.string() + " --pred " + (ds / "pred").string(), tmp);
  EXPECT_EQ(r.code, 0) << r.err;
  // desk = mean of a (1) and b (0.5) = 0.75, shelf = c (0.5): mean 0.625, std 0.125 over 2 scenes.
  EXPECT_NE(r.out.find("| all | 3 | 2 | 62.5 ± 12.5 |"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("| unlisted |"), std::string::npos) << "frames without a family are in all only";
  fs::remove_all(tmp);
}

TEST(EvalCli, SweepPrintsATablePerValueAndMarksTheBest) {
  const fs::path tmp = fresh_dir("sweep");
  scenes::TestScene s = scenes::box_on_plane();
  s.camera = synth::default_camera(160, 120);
  const synth::Rendering rendering = s.render();
  const fs::path ds = tmp / "ds";
  fs::create_directories(ds / "depth");
  write_camera_json(ds / "camera.json", s.camera);
  cv::Mat mm;
  rendering.depth.convertTo(mm, CV_16U, 1000.0);
  cv::imwrite((ds / "depth" / "000000.png").string(), mm);
  write_labels(ds / "label" / "000000.png", rendering.labels);

  const CliRun r = run_cli("eval " + ds.string() + " --sweep theta_c=0.3:0.5:0.1 --out " + (tmp / "o").string(), tmp);
  EXPECT_EQ(r.code, 0) << r.err;
  for (const char* title : {"### clutterseg theta_c=0.3", "### clutterseg theta_c=0.4", "### clutterseg theta_c=0.5",
                            "### Sweep of theta_c (all frames)"})
    EXPECT_NE(r.out.find(title), std::string::npos) << title << "\n" << r.out;
  size_t bests = 0;
  for (size_t at = r.out.find("**best**"); at != std::string::npos; at = r.out.find("**best**", at + 1)) ++bests;
  EXPECT_EQ(bests, 1u) << r.out;
  const auto summary = nlohmann::json::parse(slurp(tmp / "o" / "summary.json"));
  EXPECT_EQ(summary["sweep"]["parameter"], "theta_c");
  EXPECT_EQ(summary["sweep"]["values"].size(), 3u);
  EXPECT_DOUBLE_EQ(summary["runs"][1]["setting"]["theta_c"].get<double>(), 0.4);
  int best = 0;
  for (const auto& run : summary["runs"]) best += run["best"].get<bool>();
  EXPECT_EQ(best, 1);
  fs::remove_all(tmp);
}

// --subsample 2 scores a 640x480 set as a 320x240 sensor sees it: depth, labels and intrinsics halved, the
// scene still segmented, and the command in the summary says how the figures were made.
TEST(EvalCli, SubsampleScoresTheSceneAtTheSmallerSize) {
  const fs::path tmp = fresh_dir("subsample");
  scenes::TestScene s = scenes::box_on_plane();
  s.camera = synth::default_camera(640, 480);
  const synth::Rendering rendering = s.render();
  const fs::path ds = tmp / "ds";
  fs::create_directories(ds / "depth");
  write_camera_json(ds / "camera.json", s.camera);
  cv::Mat mm;
  rendering.depth.convertTo(mm, CV_16U, 1000.0);
  cv::imwrite((ds / "depth" / "000000.png").string(), mm);
  write_labels(ds / "label" / "000000.png", rendering.labels);

  for (const int n : {1, 2}) {
    const fs::path out = tmp / ("o" + std::to_string(n));
    const CliRun r = run_cli("eval " + ds.string() + " --subsample " + std::to_string(n) + " --out " + out.string(), tmp);
    ASSERT_EQ(r.code, 0) << r.err;
    const auto summary = nlohmann::json::parse(slurp(out / "summary.json"));
    const auto& all = group(summary["runs"][0], "all");
    EXPECT_EQ(all["failed"], 0);
    EXPECT_GE(all["scores"]["tp"]["mean"].get<double>(), 0.9) << "n = " << n;
    EXPECT_LE(all["scores"]["fp"]["mean"].get<double>(), 0.05) << "n = " << n;
    EXPECT_EQ(summary["command"].get<std::string>().find("--subsample 2") != std::string::npos, n == 2);
    // The boundary tolerance follows the scored image's size (0.3 % of its diagonal, rounded up).
    EXPECT_EQ(summary["boundary_tolerance_px"].get<int>(), n == 1 ? 3 : 2);
  }
  const CliRun r = run_cli("eval " + ds.string() + " --pred " + (ds / "label").string() + " --subsample 2", tmp);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("cannot be combined with --subsample"), std::string::npos) << r.err;
  fs::remove_all(tmp);
}

TEST(EvalCli, BadInputsAreOneLineErrors) {
  const fs::path tmp = fresh_dir("errors");
  const fs::path ds = tiny_dataset(tmp / "ds");
  CliRun r = run_cli("eval " + ds.string() + " --sweep theta_c=0.9:0.3:0.1", tmp);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("--sweep theta_c=0.9:0.3:0.1: needs STEP > 0 and STOP >= START"), std::string::npos) << r.err;
  r = run_cli("eval " + ds.string() + " --sweep nosuch=1:2:1", tmp);
  EXPECT_NE(r.err.find("--sweep: unknown parameter 'nosuch'"), std::string::npos) << r.err;
  r = run_cli("eval " + ds.string() + " --sweep patches.min_size_px=10.5:20:5", tmp);
  EXPECT_NE(r.err.find("--sweep: 'patches.min_size_px' takes whole numbers"), std::string::npos) << r.err;
  r = run_cli("eval " + ds.string() + " --sweep seed=1:2", tmp);
  EXPECT_NE(r.err.find("the range is not START:STOP:STEP"), std::string::npos) << r.err;
  r = run_cli("eval " + ds.string() + " --with nosuch", tmp);
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.err.find("unknown method 'nosuch'"), std::string::npos) << r.err;
  r = run_cli("eval " + (ds / "depth").string(), tmp);
  EXPECT_NE(r.err.find("is not a dataset folder"), std::string::npos) << r.err;
  std::ofstream(ds / "scenes.json") << "{not json";
  r = run_cli("eval " + ds.string() + " --pred " + (ds / "pred").string(), tmp);
  EXPECT_NE(r.err.find("scenes.json: is not valid JSON"), std::string::npos) << r.err;
  fs::remove_all(tmp);
}
