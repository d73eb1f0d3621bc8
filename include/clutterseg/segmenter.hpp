// The public entry point: depth image + intrinsics in, object hypotheses out.
#pragma once

#include <optional>

#include "clutterseg/normals.hpp"
#include "clutterseg/params.hpp"
#include "clutterseg/patches.hpp"
#include "clutterseg/smoothing.hpp"
#include "clutterseg/tracking.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

struct Result {
  cv::Mat object_labels;          // CV_32S, object id 1..M, 0 = nothing
  cv::Mat patch_labels;           // CV_32S, patch id 1..N after edge-pixel assignment, 0 = none
  std::vector<Patch> patches;     // statistics per patch (core pixels)
  std::vector<GraphEdge> graph;   // weighted patch graph with the cue of each link
  std::vector<Object> objects;    // sorted by id; ids 1..M, or track ids (Params::Tracking, docs/TRACKING.md)
  std::vector<HiddenObject> hidden_objects;  // tracked objects not seen in this frame (occluded, merged)
  std::optional<Plane> support_plane;  // the table, camera frame
  Timings timings_ms;             // per stage, last entry "total"

  // Intermediate images, for debugging and the debug views.
  cv::Mat depth;        // CV_32F metres after smoothing, 0 = none
  cv::Mat points;       // CV_32FC3 camera frame
  NormalPlanes normals; // unit, as x, y, z planes (CV_32F), (0,0,0) = none
  cv::Mat edge_value;   // CV_32F mean |n.n_q|
  cv::Mat edges;        // CV_8U 255 = edge
  cv::Mat core_patch_labels;  // CV_32S patches before edge pixels were assigned
};

// Stateful segmenter: keeps the temporal-smoothing window and the object tracks between frames of a
// stream; both restart on a new scene (scene_changed).
class Segmenter {
 public:
  explicit Segmenter(Params params = {});

  // depth: CV_16U (times camera.depth_unit_m) or CV_32F metres; 0/NaN = no measurement.
  // Throws Error when the depth type or intrinsics do not fit.
  Result segment(const cv::Mat& depth, const Camera& camera);

  void reset() {  // a new stream: no smoothing window, no tracks, ids from 1
    temporal_.reset();
    tracker_.reset();
  }
  const Params& params() const { return params_; }

 private:
  Params params_;
  TemporalSmoother temporal_;
  Tracker tracker_;
  cv::Mat tracked_depth_;  // the last frame's depth, for scene changes when temporal smoothing is off
};

// A frame allocates some 40 MB of images and scratch at 640x480. By default glibc hands blocks that
// large back to the kernel when they are freed (mmap, heap trimming), so every frame faults its memory
// in again page by page: a quarter of the pre-segmentation's time. This raises glibc's mmap and trim
// thresholds to 512 MB, once per process, so freed memory is reused by the next frame; the process keeps
// its peak heap. Called by Segmenter's constructor unless Params::keep_freed_memory is false; a no-op
// without glibc.
void keep_freed_memory();

// One frame, no temporal history.
Result segment(const cv::Mat& depth, const Camera& camera, const Params& params = {});

}  // namespace clutterseg
