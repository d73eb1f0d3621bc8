#include "clutterseg/segmenter.hpp"

#include <chrono>

#include "clutterseg/edges.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

// Records the time since the previous mark under a stage name.
class Stopwatch {
 public:
  explicit Stopwatch(Timings& out) : out_(out), start_(Clock::now()), last_(start_) {}
  void mark(const char* stage) {
    const auto now = Clock::now();
    out_.emplace_back(stage, std::chrono::duration<double, std::milli>(now - last_).count());
    last_ = now;
  }
  void total() { out_.emplace_back("total", std::chrono::duration<double, std::milli>(Clock::now() - start_).count()); }

 private:
  using Clock = std::chrono::steady_clock;
  Timings& out_;
  Clock::time_point start_, last_;
};

cv::Mat checked_metres(const cv::Mat& depth, const Camera& camera) {
  if (depth.empty()) throw Error("depth image is empty");
  check_camera(camera, depth.cols, depth.rows, "camera");
  cv::Mat metres = depth_to_metres(depth, camera);
  if (cv::countNonZero(metres) == 0) throw Error("depth image has no valid measurement");
  return metres;
}

}  // namespace

Segmenter::Segmenter(Params params) : params_(std::move(params)) {}

Result Segmenter::segment(const cv::Mat& depth_in, const Camera& camera) {
  const Params& p = params_;
  set_threads(p.threads);
  const PixelScale px(camera.fx, camera.fy);
  const int step = px.length(p.normals.step_px), edge_step = px.length(p.edges.step_px);
  const float jump = relative_jump_limit(p.edges, step, camera);
  const float pixel_jump = relative_jump_limit(p.edges, 1, camera);
  cv::Mat depth = checked_metres(depth_in, camera);

  Result r;
  Stopwatch watch(r.timings_ms);
  if (p.smoothing.median) depth = median_depth(depth);                           // a) 3x3 median
  watch.mark("median");
  if (p.smoothing.temporal) depth = temporal_.push(depth, p.smoothing);          // a) temporal smoothing
  watch.mark("temporal_smoothing");
  r.depth = depth;
  r.points = depth_to_points(depth, camera);                                     // point cloud
  watch.mark("pointcloud");
  r.normals = compute_normals(depth, camera, step, px.odd(p.normals.smooth_ksize), jump);  // a) normals
  watch.mark("normals");
  r.edge_value = normal_edge_value(r.normals, edge_step);                        // b) normal edges
  r.edges = edge_mask(r.edge_value, r.depth, p.edges.theta, pixel_jump);
  watch.mark("edges");
  Patches patches = extract_patches(r.edges, r.points, r.normals, p.patches,     // c) surface patches
                                    px.area(p.patches.min_size_px));
  r.core_patch_labels = patches.labels;
  r.patch_labels = patches.labels;
  r.patches = std::move(patches.patches);
  watch.mark("patches");
  watch.total();
  return r;
}

Result segment(const cv::Mat& depth, const Camera& camera, const Params& params) {
  Params single = params;
  single.smoothing.temporal = false;
  return Segmenter(single).segment(depth, camera);
}

}  // namespace clutterseg
