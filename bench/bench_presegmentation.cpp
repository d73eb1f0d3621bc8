// Pre-segmentation (paper a-c) per stage, in total and on bands of rows, its OpenCV calls alone, and the
// edge-pixel assignment (paper d); one core, the osd-kinect frames at 640x480 and 320x240. Run:
//   ./build/bench/bench_presegmentation --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "clutterseg/adjacency.hpp"
#include "clutterseg/edges.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/patches.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/smoothing.hpp"

using namespace clutterseg;

namespace {

struct Input {
  std::vector<cv::Mat> depth;  // CV_32F metres
  Camera camera;
};

// The osd-kinect frames, at full size (scale 1) or subsampled by 2 (every other pixel, as a QVGA sensor).
const Input& frames(int subsample) {
  static std::map<int, Input> cache;
  auto it = cache.find(subsample);
  if (it != cache.end()) return it->second;
  const std::filesystem::path set = std::filesystem::path(CLUTTERSEG_DATA_DIR) / "osd-kinect";
  Input in;
  in.camera = read_camera_json(set / "camera.json");
  for (const auto& f : list_dataset(set)) {
    cv::Mat d = depth_to_metres(read_depth_png(f.depth), in.camera);
    if (subsample > 1) cv::resize(d, d, d.size() / subsample, 0, 0, cv::INTER_NEAREST);
    in.depth.push_back(d);
  }
  in.camera.fx /= subsample;
  in.camera.fy /= subsample;
  in.camera.cx /= subsample;
  in.camera.cy /= subsample;
  in.camera.width /= subsample;
  in.camera.height /= subsample;
  return cache[subsample] = in;
}

// Runs `body` on every input per iteration and reports the time per frame.
template <typename Input, typename Body>
void time_per_frame(benchmark::State& state, const std::vector<Input>& inputs, const Camera& camera, Body body) {
  set_threads(1);
  keep_freed_memory();  // as a Segmenter does
  for (auto _ : state)
    for (const auto& input : inputs) benchmark::DoNotOptimize(body(input, camera));
  // Seconds of CPU per frame (shown with an SI prefix: 3.2m = 3.2 ms).
  state.counters["per_frame"] = benchmark::Counter(static_cast<double>(state.iterations() * inputs.size()),
                                                   benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

// The frames' depth (argument: subsampling) as input.
template <typename Body>
void per_frame(benchmark::State& state, Body body) {
  const Input& in = frames(static_cast<int>(state.range(0)));
  time_per_frame(state, in.depth, in.camera, body);
}

const Params kParams;

void Median(benchmark::State& s) { per_frame(s, [](const cv::Mat& d, const Camera&) { return median_depth(d); }); }

void Temporal(benchmark::State& s) {
  TemporalSmoother t;
  per_frame(s, [&](const cv::Mat& d, const Camera&) { return t.push(d, kParams.smoothing); });
}

void PointCloud(benchmark::State& s) { per_frame(s, [](const cv::Mat& d, const Camera& c) { return depth_to_points(d, c); }); }

void Normals(benchmark::State& s) {
  per_frame(s, [](const cv::Mat& d, const Camera& c) {
    const PixelScale px(c.fx, c.fy);
    const int step = px.length(kParams.normals.step_px);
    return compute_normals(d, c, step, px.odd(kParams.normals.smooth_ksize),
                           relative_jump_limit(kParams.edges, step, c));
  });
}

// The inputs of the later stages, computed once per frame (outside the timed loop).
struct Stages {
  cv::Mat depth, points, edges;
  NormalPlanes normals;
  Patches patches;
};
const std::vector<Stages>& stages(int subsample) {
  static std::map<int, std::vector<Stages>> cache;
  auto it = cache.find(subsample);
  if (it != cache.end()) return it->second;
  const Input& in = frames(subsample);
  const PixelScale px(in.camera.fx, in.camera.fy);
  const int step = px.length(kParams.normals.step_px);
  std::vector<Stages> out;
  for (const auto& raw : in.depth) {
    Stages s;
    s.depth = median_depth(raw);
    s.points = depth_to_points(s.depth, in.camera);
    s.normals = compute_normals(s.depth, in.camera, step, px.odd(kParams.normals.smooth_ksize),
                                relative_jump_limit(kParams.edges, step, in.camera));
    s.edges = edge_mask(normal_edge_value(s.normals, px.length(kParams.edges.step_px)), s.depth, kParams.edges.theta,
                        relative_jump_limit(kParams.edges, 1, in.camera));
    s.patches = extract_patches(s.edges, s.depth, in.camera, s.normals, kParams.patches, px.area(kParams.patches.min_size_px));
    out.push_back(std::move(s));
  }
  return cache[subsample] = out;
}

// The frames' precomputed stages (argument: subsampling) as input.
template <typename Body>
void per_stage_frame(benchmark::State& state, Body body) {
  time_per_frame(state, stages(static_cast<int>(state.range(0))), frames(static_cast<int>(state.range(0))).camera, body);
}

void Edges(benchmark::State& st) {
  per_stage_frame(st, [](const Stages& s, const Camera& c) {
    const PixelScale px(c.fx, c.fy);
    return edge_mask(normal_edge_value(s.normals, px.length(kParams.edges.step_px)), s.depth, kParams.edges.theta,
                     relative_jump_limit(kParams.edges, 1, c));
  });
}

void SurfacePatches(benchmark::State& st) {
  per_stage_frame(st, [](const Stages& s, const Camera& c) {
    const PixelScale px(c.fx, c.fy);
    return extract_patches(s.edges, s.depth, c, s.normals, kParams.patches, px.area(kParams.patches.min_size_px)).patches.size();
  });
}

// Paper d), the first stage after the pre-segmentation and its known hot spot.
void EdgePixelAssignment(benchmark::State& st) {
  per_stage_frame(st, [](const Stages& s, const Camera& c) {
    const PixelScale px(c.fx, c.fy);
    return assign_edge_pixels(s.patches.labels, s.points, static_cast<int>(s.patches.patches.size()),
                              px.length(kParams.adjacency.radius_px), kParams.adjacency.d_max).adjacent.size();
  });
}

// OpenCV's 3x3 median (which the median stage calls) and cv::GaussianBlur of each normal plane (which the
// normals stage used until it smoothed with its own filter), on the same images: a fixed OpenCV workload,
// the baseline for Median + Normals in the same run.
void OpenCVCalls(benchmark::State& st) {
  per_stage_frame(st, [](const Stages& s, const Camera& c) {
    const int ksize = PixelScale(c.fx, c.fy).odd(kParams.normals.smooth_ksize);
    cv::Mat median, smoothed;
    cv::medianBlur(s.depth, median, 3);
    for (const cv::Mat& plane : s.normals)
      cv::GaussianBlur(plane, smoothed, cv::Size(ksize, ksize), 0, 0, cv::BORDER_REPLICATE);
    return median.total();
  });
}

// OpenCV's 4-connected labelling of the same edge masks, which extract_patches used until it labelled
// its runs itself: the baseline for SurfacePatches (labelling, statistics and patch image together).
void OpenCVLabelling(benchmark::State& st) {
  per_stage_frame(st, [](const Stages& s, const Camera&) {
    cv::Mat labels;
    return cv::connectedComponents(s.edges == 0, labels, 4, CV_32S);
  });
}

// Everything from raw metres to patches: a) median, temporal, normals; b) edges; c) patches. (The point
// cloud is built after the patches, for stages d) to j); the patches need only the depth.)
size_t presegment(TemporalSmoother& t, const cv::Mat& raw, const Camera& c) {
  const PixelScale px(c.fx, c.fy);
  const int step = px.length(kParams.normals.step_px), edge_step = px.length(kParams.edges.step_px);
  const cv::Mat depth = t.push(median_depth(raw), kParams.smoothing);
  const NormalPlanes normals = compute_normals(depth, c, step, px.odd(kParams.normals.smooth_ksize),
                                               relative_jump_limit(kParams.edges, step, c));
  const cv::Mat edges = edge_mask(normal_edge_value(normals, edge_step), depth, kParams.edges.theta,
                                  relative_jump_limit(kParams.edges, 1, c));
  return extract_patches(edges, depth, c, normals, kParams.patches, px.area(kParams.patches.min_size_px)).patches.size();
}

// Seconds per pixel (shown with an SI prefix: 14n = 14 ns), beside the time per frame.
void per_pixel(benchmark::State& s, const std::vector<cv::Mat>& frames) {
  const double pixels = static_cast<double>(s.iterations()) * static_cast<double>(frames.size() * frames[0].total());
  s.counters["per_pixel"] = benchmark::Counter(pixels, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void Presegmentation(benchmark::State& s) {
  TemporalSmoother t;
  per_frame(s, [&](const cv::Mat& raw, const Camera& c) { return presegment(t, raw, c); });
  per_pixel(s, frames(static_cast<int>(s.range(0))).depth);
}

// The same on a band of each frame (arguments: subsampling, rows), starting a third of the way down.
// A band of a few dozen rows fits in the 1 MB L2: if cache misses mattered, its time per pixel would be
// lower than the whole frame's.
void PresegmentationBand(benchmark::State& s) {
  const Input& full = frames(static_cast<int>(s.range(0)));
  const int rows = static_cast<int>(s.range(1)), top = full.camera.height / 3;
  std::vector<cv::Mat> bands;
  for (const cv::Mat& d : full.depth) bands.push_back(d.rowRange(top, top + rows).clone());
  Camera camera = full.camera;
  camera.height = rows;
  camera.cy -= top;
  TemporalSmoother t;
  time_per_frame(s, bands, camera, [&](const cv::Mat& raw, const Camera& c) { return presegment(t, raw, c); });
  per_pixel(s, bands);
}

}  // namespace

// Argument: subsampling (1 = 640x480, 2 = 320x240).
BENCHMARK(Median)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(Temporal)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(PointCloud)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(Normals)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(Edges)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(SurfacePatches)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(EdgePixelAssignment)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(OpenCVCalls)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(OpenCVLabelling)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(Presegmentation)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);
BENCHMARK(PresegmentationBand)->Args({1, 60})->Args({1, 120})->Args({2, 30})->Args({2, 60})->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
