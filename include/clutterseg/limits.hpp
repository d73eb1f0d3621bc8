// What clutterseg accepts: the valid range of every parameter, the largest frame and the intrinsics it
// takes. Checked in one place each, so the CLI, the JSON config, Python and ROS refuse the same inputs
// with the same one-line message (docs/RELIABILITY.md).
#pragma once

#include <cstdint>
#include <string>

#include "clutterseg/params.hpp"

namespace clutterseg {

// Throws Error("parameter 'KEY' = VALUE: must be ...") for the first parameter outside its range; KEY is
// the name of --dump-config (e.g. graph.theta_c). The ranges are in src/limits.cpp, one line per key, and
// docs/RELIABILITY.md. Called by the Segmenter's constructor and by params_from_json.
void validate(const Params& params);

// Largest frame: 2^23 pixels (a 3840x2160 sensor fits) and 16384 pixels a side. The pipeline needs about 85
// bytes per pixel besides a fixed ~100 MB (docs/RELIABILITY.md), so the largest frame takes about 0.8 GB.
inline constexpr int kMaxFrameSide = 16384;
inline constexpr std::int64_t kMaxFramePixels = std::int64_t{1} << 23;

// Throws Error("<what>: WxH ...") when a frame of this size is empty or beyond the limits above.
void check_frame_size(std::int64_t width, std::int64_t height, const std::string& what);

// Field of view the intrinsics may describe: between 1 and 175 degrees across the image (fx at most
// 57.3 x width, at least 0.022 x width; fy likewise with the height). Pixel sizes derived from fx, fy
// (PixelScale) are bounded besides: a factor above kMaxPixelScale is taken as kMaxPixelScale.
inline constexpr double kMinFovDeg = 1.0, kMaxFovDeg = 175.0;

// Metres per step of 16-bit depth: 1 um to 1 m (a larger unit would turn depths into infinities).
inline constexpr double kMinDepthUnit = 1e-6, kMaxDepthUnit = 1.0;

}  // namespace clutterseg
