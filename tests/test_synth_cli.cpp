// `clutterseg synth` from the command line: the dataset it writes, determinism and its errors.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sys/wait.h>
#include <unistd.h>
#include <nlohmann/json.hpp>
#include <sstream>

#include "clutterseg/io.hpp"
#include "clutterseg/synth/dataset.hpp"

namespace fs = std::filesystem;
using namespace clutterseg;

namespace {

struct CliRun {
  int code = 0;
  std::string err;
};

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("clutterseg_synth_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir;
}

CliRun run_cli(const std::string& args) {
  const fs::path err = fresh_dir("stderr");
  const std::string cmd = std::string(CLUTTERSEG_CLI) + " synth " + args + " >/dev/null 2>" + err.string();
  const int status = std::system(cmd.c_str());
  CliRun r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::stringstream ss;
  ss << in.rdbuf();
  r.err = ss.str();
  fs::remove(err);
  return r;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST(SynthCli, WritesTheDatasetLayoutWithScenesJson) {
  const fs::path out = fresh_dir("layout");
  ASSERT_EQ(run_cli("--preset mixed --frames 3 --seed 5 --size 160x120 --out " + out.string()).code, 0);
  const Camera cam = read_camera_json(out / "camera.json");
  EXPECT_EQ(cam.width, 160);
  EXPECT_EQ(cam.height, 120);
  const auto frames = list_dataset(out);
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].name, "000000");
  EXPECT_EQ(frames[2].name, "000002");
  const auto scenes = nlohmann::json::parse(read_bytes(out / "scenes.json"));
  EXPECT_EQ(scenes["preset"], "mixed");
  EXPECT_EQ(scenes["sensor"], "kinect-v1");
  EXPECT_EQ(scenes["seed"], 5);
  ASSERT_EQ(scenes["frames"].size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const auto& f = scenes["frames"][i];
    EXPECT_EQ(f["name"], frames[i].name);
    EXPECT_EQ(f["family"], "mixed");
    // Label image: ids 1..n, each with the visible pixel count the JSON gives.
    const cv::Mat labels = read_label_png(*frames[i].label);
    double max_id = 0;
    cv::minMaxLoc(labels, nullptr, &max_id);
    EXPECT_LE(max_id, static_cast<double>(f["objects"].size()));
    for (const auto& o : f["objects"]) {
      EXPECT_EQ(o["size"].size(), 3u);
      EXPECT_EQ(o["pose"]["position"].size(), 3u);
      EXPECT_EQ(o["pose"]["rotation_xyz_deg"].size(), 3u);
      EXPECT_EQ(cv::countNonZero(labels == o["id"].get<int>()), o["visible_pixels"].get<int>());
    }
    EXPECT_EQ(read_depth_png(frames[i].depth).size(), labels.size());
    ASSERT_TRUE(frames[i].color.has_value());
  }
  fs::remove_all(out);
}

TEST(SynthCli, RotationInScenesJsonRebuildsThePose) {
  const Camera cam = synth::default_camera(160, 120);
  const auto g = synth::generate_scene("lying-cylinder-occluded", 3, 0, cam);
  const fs::path out = fresh_dir("pose");
  ASSERT_EQ(run_cli("--preset lying-cylinder-occluded --frames 1 --seed 3 --size 160x120 --sensor ideal --out " + out.string()).code, 0);
  const auto scenes = nlohmann::json::parse(read_bytes(out / "scenes.json"));
  for (size_t i = 0; i < g.objects.size(); ++i) {
    const auto r = scenes["frames"][0]["objects"][i]["pose"]["rotation_xyz_deg"];
    const double a = r[0].get<double>() * M_PI / 180, b = r[1].get<double>() * M_PI / 180, c = r[2].get<double>() * M_PI / 180;
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(c, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(b, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX())).toRotationMatrix();
    EXPECT_TRUE(R.isApprox(g.objects[i].pose.linear(), 1e-5));
  }
  fs::remove_all(out);
}

TEST(SynthCli, SameSeedSameBytesForAnyThreadCount) {
  const fs::path a = fresh_dir("det_a"), b = fresh_dir("det_b"), c = fresh_dir("det_c");
  const std::string common = "--preset complex --frames 4 --size 160x120 ";
  ASSERT_EQ(run_cli(common + "--seed 9 --threads 1 --out " + a.string()).code, 0);
  ASSERT_EQ(run_cli(common + "--seed 9 --threads 2 --out " + b.string()).code, 0);
  ASSERT_EQ(run_cli(common + "--seed 10 --out " + c.string()).code, 0);
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), a);
    EXPECT_EQ(read_bytes(e.path()), read_bytes(b / rel)) << rel;
    ++files;
  }
  EXPECT_EQ(files, 2 + 3 * 4);
  EXPECT_NE(read_bytes(a / "depth" / "000000.png"), read_bytes(c / "depth" / "000000.png"));
  for (const auto& d : {a, b, c}) fs::remove_all(d);
}

TEST(SynthCli, BadFlagsGiveAOneLineErrorAndNonZeroExit) {
  const fs::path out = fresh_dir("bad");
  const std::string o = " --out " + out.string();
  struct Case {
    std::string args, mentions;
  };
  const Case cases[] = {
      {"--preset nope --frames 1" + o, "nope"},
      {"--preset cup --frames 0" + o, "--frames"},
      {"--preset cup --frames -3" + o, "--frames"},
      {"--preset cup --size 640" + o, "--size"},
      {"--preset cup --size 5x5" + o, "5x5"},
      {"--preset cup --sensor kinect-v3" + o, "kinect-v3"},
      {"--preset cup", "--out"},
      {"--frames 2" + o, "--preset"},
      {"--preset cup --camera /nonexistent/camera.json" + o, "camera"},
  };
  for (const auto& c : cases) {
    const CliRun r = run_cli(c.args);
    EXPECT_NE(r.code, 0) << c.args;
    EXPECT_NE(r.err.find(c.mentions), std::string::npos) << c.args << " -> " << r.err;
    const std::string first_line = r.err.substr(0, r.err.find('\n'));
    EXPECT_FALSE(first_line.empty()) << c.args;
  }
  // The library's own errors are exactly one line; nothing is written for a bad option.
  const CliRun r = run_cli("--preset cup --frames 0" + o);
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_FALSE(fs::exists(out / "scenes.json"));
  // A folder that holds something else is not overwritten without --overwrite.
  fs::create_directories(out);
  std::ofstream(out / "mine.txt") << "keep";
  const CliRun busy = run_cli("--preset cup --frames 1" + o);
  EXPECT_NE(busy.code, 0);
  EXPECT_NE(busy.err.find("--overwrite"), std::string::npos);
  EXPECT_EQ(run_cli("--preset cup --frames 1 --overwrite" + o).code, 0);
  EXPECT_TRUE(fs::exists(out / "mine.txt"));
  fs::remove_all(out);
}
