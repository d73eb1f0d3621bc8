// Paper a): depth smoothing. Depth is CV_32F in metres, 0 = no measurement.
#pragma once

#include <deque>

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// Converts uint16 depth (times camera.depth_unit_m) or float metres (NaN/inf/<=0 = none) to CV_32F
// metres with 0 = none. Throws Error if the type is neither.
cv::Mat depth_to_metres(const cv::Mat& depth, const Camera& camera);

// The validation every frame gets first (Segmenter, Pipeline): a non-empty depth image whose intrinsics fit
// (check_camera) and that holds at least one valid measurement; returned in metres. Throws Error.
cv::Mat checked_metres(const cv::Mat& depth, const Camera& camera);

// 3x3 median over the valid neighbours of each valid pixel; invalid pixels stay invalid.
cv::Mat median_depth(const cv::Mat& depth);

// The next frame shows another scene than the previous one: more than scene_change_share of the pixels
// measured in both moved by more than the temporal band (a cut in a video, a folder of unrelated frames,
// a camera that moved), or the size changed.
bool scene_changed(const cv::Mat& previous, const cv::Mat& next, const Params::Smoothing& params);

// Motion-sensitive temporal smoothing over the last n frames: a pixel becomes the mean of the window's
// values that lie within band = k * z^2 of its newest value, so static surfaces are averaged and moving
// ones keep their newest depth (no motion blur). A pixel invalid in the newest frame stays invalid.
// A new scene empties the window first (scene_changed): frames of unrelated scenes are never averaged.
class TemporalSmoother {
 public:
  // Adds a copy of `depth` to the window and returns the smoothed newest frame.
  cv::Mat push(const cv::Mat& depth, const Params::Smoothing& params);
  // The same, keeping `depth`'s buffer in the window instead of a copy: for a frame nothing else will
  // write to (the median's output, say), one copy less.
  cv::Mat push(cv::Mat&& depth, const Params::Smoothing& params);
  void reset() { window_.clear(); }
  // The last push emptied the window first: a new scene (or the first frame).
  bool restarted() const { return restarted_; }
  int size() const { return static_cast<int>(window_.size()); }

 private:
  cv::Mat make_room(const cv::Mat& next, const Params::Smoothing& params);  // the buffer of the frame that leaves
  cv::Mat smooth_newest(const Params::Smoothing& params) const;
  std::deque<cv::Mat> window_;  // newest last
  bool restarted_ = false;
};

}  // namespace clutterseg
