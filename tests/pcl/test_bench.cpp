// `clutterseg bench` runs clutterseg and a PCL baseline on the same frames and writes one markdown report.
#include <gtest/gtest.h>

#include <cstdlib>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "clutterseg/io.hpp"
#include "scenes.hpp"

namespace fs = std::filesystem;
using namespace clutterseg;

namespace {

// A two-frame dataset folder (SPEC Sec. 3) of the box-on-table scene at 640x480, depth in millimetres.
fs::path box_dataset() {
  const fs::path dir = fs::temp_directory_path() / ("clutterseg_test_bench_" + std::to_string(::getpid()));
  fs::create_directories(dir / "depth");
  auto scene = scenes::box_on_plane();
  scene.camera = synth::default_camera(640, 480);
  cv::Mat mm;
  scene.render().depth.convertTo(mm, CV_16U, 1000.0);
  write_camera_json(dir / "camera.json", scene.camera);
  write_png_atomic(dir / "depth" / "000001.png", mm);
  write_png_atomic(dir / "depth" / "000002.png", mm);
  return dir;
}

int run(const std::string& args) { return std::system((std::string(CLUTTERSEG_CLI) + " " + args).c_str()); }

std::string read_text(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

TEST(Bench, ReportsEveryMethodOnTheSameFramesWithTheRatioToClutterseg) {
  const fs::path data = box_dataset();
  const fs::path out = data / "bench.md";
  ASSERT_EQ(run("bench " + data.string() + " --with organized --repeat 1 --warmup 1 --out " + out.string() + " > /dev/null"), 0);
  const std::string md = read_text(out);
  EXPECT_NE(md.find("| clutterseg | 1 | 2 |"), std::string::npos) << md;   // one core, both frames timed
  EXPECT_NE(md.find("| organized | 1 | 2 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 1.00x |"), std::string::npos) << md;               // clutterseg is the reference
  EXPECT_NE(md.find("| total |"), std::string::npos) << md;               // per-stage table
  EXPECT_NE(md.find("cores (nproc)"), std::string::npos) << md;
}

TEST(Bench, UnknownMethodIsAnErrorBeforeAnythingRuns) {
  const fs::path data = box_dataset();
  EXPECT_NE(run("bench " + data.string() + " --with nosuchmethod --out " + (data / "never.md").string() + " > /dev/null 2>&1"), 0);
  EXPECT_FALSE(fs::exists(data / "never.md"));
}

TEST(Bench, SubsampleTimesTheSameFramesAtHalfTheResolution) {
  const fs::path data = box_dataset();
  const fs::path out = data / "half.md";
  ASSERT_EQ(run("bench " + data.string() + " --subsample 2 --repeat 1 --out " + out.string() + " > /dev/null"), 0);
  const std::string md = read_text(out);
  EXPECT_NE(md.find("frames: 2 of 320x240"), std::string::npos) << md;
  EXPECT_NE(md.find("--subsample 2"), std::string::npos) << md;  // the command that reproduces it
  EXPECT_NE(run("bench " + data.string() + " --subsample 0 > /dev/null 2>&1"), 0);
}
