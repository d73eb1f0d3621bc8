#include "clutterseg/io.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "clutterseg/limits.hpp"

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
  if (!j.is_object()) fail(path, "needs numbers fx, fy, cx, cy, width, height (is no JSON object)");
  // Numbers are checked before they are converted: a float beyond an int's range (width 1e40) would be
  // undefined behaviour.
  const auto number = [&](const char* key) {
    if (!j.contains(key) || !j.at(key).is_number())
      fail(path, std::string("needs numbers fx, fy, cx, cy, width, height ('") + key + "' is missing or no number)");
    const double v = j.at(key).get<double>();
    if (!std::isfinite(v)) fail(path, std::string("'") + key + "' is not a finite number");
    return v;
  };
  const auto size = [&](const char* key) {
    if (!j.contains(key) || !j.at(key).is_number_integer())
      fail(path, std::string("'") + key + "' must be a whole number of pixels");
    const bool negative = j.at(key).is_number_integer() && !j.at(key).is_number_unsigned() && j.at(key).get<std::int64_t>() < 0;
    if (negative || j.at(key).get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxFrameSide))
      fail(path, std::string("'") + key + "' = " + j.at(key).dump() + " is outside [1, " + std::to_string(kMaxFrameSide) + "]");
    return static_cast<int>(j.at(key).get<std::int64_t>());
  };
  Camera c;
  c.fx = number("fx");
  c.fy = number("fy");
  c.cx = number("cx");
  c.cy = number("cy");
  c.width = size("width");
  c.height = size("height");
  if (j.contains("depth_unit_m")) c.depth_unit_m = number("depth_unit_m");
  if (!(c.fx > 0 && c.fy > 0 && c.width > 0 && c.height > 0 && c.depth_unit_m > 0))
    fail(path, "fx, fy, width, height and depth_unit_m must be positive");
  if (!(c.depth_unit_m >= kMinDepthUnit && c.depth_unit_m <= kMaxDepthUnit))
    fail(path, "depth_unit_m " + std::to_string(c.depth_unit_m) + " is outside [1e-6, 1] metres per step");
  return c;
}

void write_camera_json(const fs::path& path, const Camera& c) {
  nlohmann::json j = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy},
                      {"width", c.width}, {"height", c.height}, {"depth_unit_m", c.depth_unit_m}};
  write_text_atomic(path, j.dump(1) + "\n");
}

cv::Mat read_png(const fs::path& path, int imread_flags) {
  if (!fs::exists(path)) fail(path, "no such file");
  if (fs::is_directory(path)) fail(path, "is a folder, not an image");
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (ext != ".png") fail(path, "is not a .png file (images are read as PNG only)");
  std::error_code ec;
  const auto bytes = fs::file_size(path, ec);
  if (ec) fail(path, "cannot be read (" + ec.message() + ")");
  // The largest frame, stored uncompressed, with room for ancillary chunks.
  constexpr std::uintmax_t kMaxBytes = static_cast<std::uintmax_t>(kMaxFramePixels) * 8 + (16u << 20);
  if (bytes > kMaxBytes) fail(path, "is larger than any PNG frame clutterseg takes (" + std::to_string(bytes) + " bytes)");
  std::vector<uchar> data(static_cast<size_t>(bytes));
  {
    std::ifstream in(path, std::ios::binary);
    if (!in || !in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(data.size())))
      fail(path, "cannot be read");
  }
  // PNG signature, then the IHDR chunk (length 13) with width and height: checked here, so that no other
  // decoder takes the bytes and no frame beyond the limits is allocated.
  static constexpr uchar kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (data.size() < 33 || !std::equal(kSignature, kSignature + 8, data.begin()))
    fail(path, "is not a PNG file (no PNG signature)");
  if (!(data[8] == 0 && data[9] == 0 && data[10] == 0 && data[11] == 13 && std::equal(data.begin() + 12, data.begin() + 16, "IHDR")))
    fail(path, "is not a valid PNG file (no IHDR chunk first)");
  const auto be32 = [&](size_t at) {
    return std::int64_t{data[at]} << 24 | std::int64_t{data[at + 1]} << 16 | std::int64_t{data[at + 2]} << 8 | data[at + 3];
  };
  check_frame_size(be32(16), be32(20), path.string());
  cv::Mat image;
  try {
    image = cv::imdecode(data, imread_flags);
  } catch (const cv::Exception& e) {
    fail(path, "cannot be decoded as PNG (" + std::string(e.err) + ")");
  }
  if (image.empty()) fail(path, "cannot be decoded as PNG (damaged or truncated)");
  return image;
}

cv::Mat read_depth_png(const fs::path& path) {
  cv::Mat depth = read_png(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
  if (depth.type() != CV_16UC1)
    fail(path, "is a " + type_name(depth) + " image; depth must be a 16-bit single-channel PNG");
  return depth;
}

cv::Mat read_label_png(const fs::path& path) {
  cv::Mat labels = read_png(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
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
