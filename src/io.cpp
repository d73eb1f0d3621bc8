#include "clutterseg/io.hpp"

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

namespace clutterseg {

namespace {

[[noreturn]] void fail(const fs::path& path, const std::string& problem) {
  throw Error(path.string() + ": " + problem);
}

std::string type_name(const cv::Mat& m) {
  const char* depths[] = {"8-bit", "8-bit signed", "16-bit", "16-bit signed", "32-bit int", "float", "double", "half"};
  return std::string(depths[m.depth()]) + " " + std::to_string(m.channels()) + "-channel";
}

// A temporary name beside `path` that keeps its extension (OpenCV picks the encoder from it).
fs::path temporary_beside(const fs::path& path) {
  return path.parent_path() / (path.stem().string() + ".partial" + path.extension().string());
}

// Moves the finished temporary file into place; on failure removes it, so nothing is left behind.
void replace_with(const fs::path& tmp, const fs::path& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    fail(path, "cannot be written (" + ec.message() + ")");
  }
}

}  // namespace

Camera read_camera_json(const fs::path& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot be opened");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const std::exception& e) {
    fail(path, std::string("is not valid JSON (") + e.what() + ")");
  }
  Camera c;
  try {
    c.fx = j.at("fx").get<double>();
    c.fy = j.at("fy").get<double>();
    c.cx = j.at("cx").get<double>();
    c.cy = j.at("cy").get<double>();
    c.width = j.at("width").get<int>();
    c.height = j.at("height").get<int>();
    c.depth_unit_m = j.value("depth_unit_m", 0.001);
  } catch (const std::exception& e) {
    fail(path, std::string("needs numbers fx, fy, cx, cy, width, height (") + e.what() + ")");
  }
  if (!(c.fx > 0 && c.fy > 0 && c.width > 0 && c.height > 0 && c.depth_unit_m > 0))
    fail(path, "fx, fy, width, height and depth_unit_m must be positive");
  return c;
}

void write_camera_json(const fs::path& path, const Camera& c) {
  nlohmann::json j = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy},
                      {"width", c.width}, {"height", c.height}, {"depth_unit_m", c.depth_unit_m}};
  write_text_atomic(path, j.dump(1) + "\n");
}

cv::Mat read_depth_png(const fs::path& path) {
  if (!fs::exists(path)) fail(path, "no such file");
  if (fs::is_directory(path)) fail(path, "is a folder, not a depth image");
  cv::Mat depth = cv::imread(path.string(), cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (depth.empty()) fail(path, "cannot be read as an image");
  if (depth.type() != CV_16UC1)
    fail(path, "is a " + type_name(depth) + " image; depth must be a 16-bit single-channel PNG");
  return depth;
}

cv::Mat read_label_png(const fs::path& path) {
  if (!fs::exists(path)) fail(path, "no such file");
  cv::Mat labels = cv::imread(path.string(), cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (labels.empty()) fail(path, "cannot be read as an image");
  if (labels.channels() != 1 || (labels.depth() != CV_16U && labels.depth() != CV_8U))
    fail(path, "is a " + type_name(labels) + " image; labels must be a single-channel 8- or 16-bit PNG");
  cv::Mat out;
  labels.convertTo(out, CV_32S);
  return out;
}

std::vector<FrameFiles> list_dataset(const fs::path& dataset) {
  const fs::path depth_dir = dataset / "depth";
  if (!fs::is_directory(depth_dir)) fail(dataset, "is not a dataset folder (no depth/ inside)");
  std::vector<FrameFiles> frames;
  for (const auto& entry : fs::directory_iterator(depth_dir)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".png") continue;
    FrameFiles f;
    f.name = entry.path().stem().string();
    f.depth = entry.path();
    if (auto c = dataset / "color" / (f.name + ".png"); fs::exists(c)) f.color = c;
    if (auto l = dataset / "label" / (f.name + ".png"); fs::exists(l)) f.label = l;
    frames.push_back(std::move(f));
  }
  std::sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
  if (frames.empty()) fail(depth_dir, "holds no .png depth frames");
  return frames;
}

void write_png_atomic(const fs::path& path, const cv::Mat& image) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const fs::path tmp = temporary_beside(path);
  bool ok = false;
  try {
    ok = cv::imwrite(tmp.string(), image);
  } catch (const cv::Exception& e) {
    ok = false;
  }
  if (!ok) {
    std::error_code ec;
    fs::remove(tmp, ec);
    fail(path, "cannot be written");
  }
  replace_with(tmp, path);
}

void write_text_atomic(const fs::path& path, const std::string& text) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
  const fs::path tmp = temporary_beside(path);
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      fail(path, "cannot be written");
    }
  }
  replace_with(tmp, path);
}

cv::Mat labels_to_u16(const cv::Mat& labels) {
  double max_id = 0;
  cv::minMaxLoc(labels, nullptr, &max_id);
  if (max_id > 65535) throw Error("label image has ids above 65535");
  cv::Mat out;
  labels.convertTo(out, CV_16U);
  return out;
}

}  // namespace clutterseg
