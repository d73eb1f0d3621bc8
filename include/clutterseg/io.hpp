// Reading depth frames and intrinsics; atomic writing of outputs.
#pragma once

#include <filesystem>
#include <optional>

#include "clutterseg/types.hpp"

namespace clutterseg {

namespace fs = std::filesystem;

// camera.json of SPEC Sec. 3: {fx, fy, cx, cy, width, height, depth_unit_m}.
Camera read_camera_json(const fs::path& path);
void write_camera_json(const fs::path& path, const Camera& camera);

// A .png file decoded as PNG only (signature and IHDR checked first, frame size within limits.hpp);
// imread_flags as for cv::imread. Throws Error naming the file for anything else.
cv::Mat read_png(const fs::path& path, int imread_flags);

// 16-bit single-channel PNG depth; throws Error naming the file for anything else.
cv::Mat read_depth_png(const fs::path& path);

// uint16 label PNG (0 = none) as CV_32S.
cv::Mat read_label_png(const fs::path& path);

// One frame of a dataset folder (SPEC Sec. 3).
struct FrameFiles {
  std::string name;                // file stem, e.g. "000001"
  fs::path depth;                  // <set>/depth/NAME.png (or a .pcd for PCD input)
  std::optional<fs::path> color;   // <set>/color/NAME.png
  std::optional<fs::path> label;   // <set>/label/NAME.png
};

// Frames of a dataset folder in name (= time) order.
std::vector<FrameFiles> list_dataset(const fs::path& dataset);

// Writes to a temporary file beside `path` and renames, so a failure leaves nothing half-written.
void write_png_atomic(const fs::path& path, const cv::Mat& image);
void write_text_atomic(const fs::path& path, const std::string& text);

// uint16 copy of a CV_32S label image (ids above 65535 are an Error).
cv::Mat labels_to_u16(const cv::Mat& labels);

}  // namespace clutterseg
