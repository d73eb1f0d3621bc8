// Organized PCD input through PCL's reader (library clutterseg_pcl; the core does not need PCL).
#pragma once

#include <filesystem>
#include <optional>

#include "clutterseg/types.hpp"

namespace clutterseg {

struct PcdFrame {
  cv::Mat depth;   // CV_32F metres (z), 0 = no measurement (NaN in the file)
  cv::Mat color;   // CV_8UC3 BGR when the cloud has rgb/rgba, else empty
  Camera camera;   // the given intrinsics, or ones recovered from the organized cloud
};

// Reads an organized PCD (height > 1). Without `camera`, fx, fy, cx, cy are fitted by least squares to
// x = (u - cx) z / fx, y = (v - cy) z / fy over the valid points. Throws Error naming the file when it
// cannot be read, is not organized, has no x/y/z, holds no valid point, or does not fit `camera`.
PcdFrame read_organized_pcd(const std::filesystem::path& path, const std::optional<Camera>& camera = {});

}  // namespace clutterseg
