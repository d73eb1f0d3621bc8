#include "clutterseg/segmenter.hpp"

#include <chrono>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "clutterseg/adjacency.hpp"
#include "clutterseg/cutfree.hpp"
#include "clutterseg/edges.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/objects.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/remaining.hpp"

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

// Stand-in for f-i until the graph cut is merged: objects = connected components of the links (the
// paper's "adjacency + cut-free only" comparison). Fills the weighted graph (1/deg, symmetrised).
struct Components {
  std::vector<int> object_of_patch;
  std::vector<float> cut_cost;  // +inf for one patch; 0 (unknown) for several until the graph cut
};
Components linked_components(int num_patches, const std::vector<PatchPair>& links, std::vector<GraphEdge>& graph) {
  std::vector<int> parent(static_cast<size_t>(num_patches));
  std::iota(parent.begin(), parent.end(), 0);
  auto root = [&](int x) { while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])]; return x; };
  std::vector<int> degree(static_cast<size_t>(num_patches), 0);
  for (const auto& [a, b] : links) {
    parent[static_cast<size_t>(root(a))] = root(b);
    ++degree[static_cast<size_t>(a)];
    ++degree[static_cast<size_t>(b)];
  }
  for (const auto& [a, b] : links)
    graph.push_back({a, b, Cue::Adjacent, 0.5f / static_cast<float>(degree[static_cast<size_t>(a)]) + 0.5f / static_cast<float>(degree[static_cast<size_t>(b)])});
  std::vector<int> object_of_root(static_cast<size_t>(num_patches), -1);
  Components c;
  for (int p = 0; p < num_patches; ++p) {
    int& o = object_of_root[static_cast<size_t>(root(p))];
    if (o < 0) {
      o = static_cast<int>(c.cut_cost.size());
      c.cut_cost.push_back(std::numeric_limits<float>::infinity());
    } else {
      c.cut_cost[static_cast<size_t>(o)] = 0.f;
    }
    c.object_of_patch.push_back(o);
  }
  return c;
}

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
  r.patches = std::move(patches.patches);
  watch.mark("patches");
  const int num_patches = static_cast<int>(r.patches.size());
  const Assignment assignment = assign_edge_pixels(r.core_patch_labels, r.points, num_patches,   // d) adjacency
                                                   px.length(p.adjacency.radius_px), p.adjacency.d_max);
  r.patch_labels = assignment.labels;
  watch.mark("assignment");
  const std::vector<PatchPair> links = p.cutfree.enabled                                  // e) cut-free
      ? cut_free_pairs(assignment.adjacent, r.patches, r.points, p.cutfree, p.seed) : assignment.adjacent;
  watch.mark("cutfree");
  const Components parts = linked_components(num_patches, links, r.graph);               // f-i) stand-in
  watch.mark("graph");
  r.object_labels = assign_remaining(r.patch_labels, parts.object_of_patch,                      // j) remaining
                                     static_cast<int>(parts.cut_cost.size()), r.points, p.remaining,
                                     px.area(p.remaining.tiny_px), p.seed);
  watch.mark("remaining");
  r.objects = describe_objects(r.object_labels, r.points, parts.object_of_patch, parts.cut_cost, camera);  // objects
  r.support_plane = find_support(r.objects, r.patches, r.object_labels, r.points, p.support);   // table, walls
  if (r.support_plane)                                                           // objects merged into it
    split_support(r.object_labels, r.objects, *r.support_plane, r.points, p.support, px.area(p.patches.min_size_px), camera);
  watch.mark("objects");
  watch.total();
  return r;
}

Result segment(const cv::Mat& depth, const Camera& camera, const Params& params) {
  Params single = params;
  single.smoothing.temporal = false;
  return Segmenter(single).segment(depth, camera);
}

}  // namespace clutterseg
