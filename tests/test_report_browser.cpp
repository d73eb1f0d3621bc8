// report.html in a real browser: headless Chromium opens the page `clutterseg eval` wrote, and the DOM
// and a screenshot show the tables, the plots and the pictures. Needs Debian's chromium (scripts/setup.sh).
// CLUTTERSEG_SAVE_SCREENSHOT=docs/images/eval-report.png keeps the screenshot.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int shell(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Two frames of the ycbv-0000 sequence and the ycbv-0003 frame, as two families.
fs::path small_real_dataset(const fs::path& root) {
  const fs::path data = CLUTTERSEG_DATA_DIR;
  for (const char* sub : {"depth", "color", "label"}) {
    fs::create_directories(root / sub);
    for (const auto& [set, name] : {std::pair{"ycbv-0000", "000001"}, {"ycbv-0000", "000002"}, {"ycbv-0003", "000138"}})
      fs::copy_file(data / set / sub / (std::string(name) + ".png"), root / sub / (std::string(name) + ".png"));
  }
  fs::copy_file(data / "ycbv-0000" / "camera.json", root / "camera.json");  // both videos share the camera
  std::ofstream(root / "scenes.json") << R"({"frames": [
    {"name": "000001", "family": "video 0000", "scene": "0000"},
    {"name": "000002", "family": "video 0000", "scene": "0000"},
    {"name": "000138", "family": "video 0003", "scene": "0003"}]})";
  return root;
}

}  // namespace

TEST(ReportBrowser, ChromiumShowsTablesPlotsAndPictures) {
  ASSERT_EQ(shell("command -v chromium >/dev/null"), 0) << "chromium is missing: run scripts/setup.sh";
  ASSERT_TRUE(fs::exists(fs::path(CLUTTERSEG_DATA_DIR) / "ycbv-0000")) << "no data at " << CLUTTERSEG_DATA_DIR;
  const fs::path tmp = fs::temp_directory_path() / ("clutterseg-report-" + std::to_string(getpid()));
  fs::remove_all(tmp);
  const fs::path ds = small_real_dataset(tmp / "ds"), out = tmp / "out";
  ASSERT_EQ(shell(std::string(CLUTTERSEG_CLI) + " eval " + ds.string() + " --sweep theta_c=0.4:0.5:0.1 --out " +
                  out.string() + " >" + (tmp / "eval.txt").string() + " 2>&1"),
            0)
      << slurp(tmp / "eval.txt");
  ASSERT_TRUE(fs::exists(out / "report.html"));

  const std::string chromium =
      "timeout 120 chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run "
      "--disable-background-networking --disable-component-update --disable-sync --user-data-dir=" +
      (tmp / "profile").string() + " --window-size=1280,2000 ";
  const std::string url = "file://" + fs::absolute(out / "report.html").string();
  ASSERT_EQ(shell(chromium + "--dump-dom " + url + " >" + (tmp / "dom.html").string() + " 2>/dev/null"), 0);
  const std::string dom = slurp(tmp / "dom.html");

  // The summary tables: one per swept value, rows for all frames and each family, both metric families.
  EXPECT_NE(dom.find("<table class=\"summary\" id=\"summary-0\">"), std::string::npos);
  EXPECT_NE(dom.find("<caption>clutterseg theta_c=0.4"), std::string::npos);
  for (const char* text : {"<th>tp</th>", "<th>Overlap F</th>", "<th>Boundary F</th>", "<th>%&gt;=75</th>",
                           "<td>all</td><td>3</td><td>2</td>", "<td>video 0000</td><td>2</td><td>1</td>",
                           "<td>video 0003</td><td>1</td><td>1</td>", "id=\"sweep-table\"", "class=\"best\"",
                           "<table class=\"errors\" id=\"errors-0\">", "<th>R: merged away</th>", "<th>P: table/bg</th>"})
    EXPECT_NE(dom.find(text), std::string::npos) << text;
  // The matplotlib plots and the per-frame pictures, all decoded by the browser.
  for (const char* id : {"plot-scatter", "plot-families", "plot-errors", "plot-timings", "plot-sweep", "frame-000001",
                         "frame-000138"})
    EXPECT_NE(dom.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  EXPECT_EQ(dom.find("id=\"plot-note\""), std::string::npos) << "plots were not drawn";
  // 5 plots + 3 frames x (image, ground truth, prediction of the best theta_c).
  EXPECT_NE(dom.find("data-images-decoded=\"14/14\""), std::string::npos);

  const fs::path shot = tmp / "report.png";
  ASSERT_EQ(shell(chromium + "--screenshot=" + shot.string() + " " + url + " >/dev/null 2>&1"), 0);
  const cv::Mat png = cv::imread(shot.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(png.cols, 1280);
  EXPECT_EQ(png.rows, 2000);
  // Not blank: a white page with text has few non-white pixels; tables, plots and photos have many.
  cv::Mat grey;
  cv::cvtColor(png, grey, cv::COLOR_BGR2GRAY);
  EXPECT_GT(cv::countNonZero(grey < 200), png.total() / 20);
  cv::Scalar mean, sd;
  cv::meanStdDev(grey, mean, sd);
  EXPECT_GT(sd[0], 20);
  if (const char* keep = std::getenv("CLUTTERSEG_SAVE_SCREENSHOT"); keep && *keep)
    fs::copy_file(shot, keep, fs::copy_options::overwrite_existing);
  fs::remove_all(tmp);
}
