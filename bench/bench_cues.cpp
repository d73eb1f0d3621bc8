// Paper f/g and h on real frames: co-planarity and curvature matching after the pre-segmentation,
// one frame per benchmark, single thread. No adjacency is given (stage d runs elsewhere), so every
// pair of patches is a candidate: an upper bound on the work in the full pipeline.
//   ./build/bench/bench_cues --benchmark_min_time=0.2s
#include <benchmark/benchmark.h>

#include "clutterseg/coplanarity.hpp"
#include "clutterseg/curvature.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/segmenter.hpp"

using namespace clutterseg;

namespace {

struct Frame {
  std::string name;
  Camera camera;
  Result result;
};

const std::vector<Frame>& frames() {
  static const std::vector<Frame> all = [] {
    std::vector<Frame> out;
    const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "osd-kinect";
    if (!fs::exists(set)) return out;
    const Camera camera = read_camera_json(set / "camera.json");
    Params params;
    params.threads = 1;
    for (const auto& f : list_dataset(set)) out.push_back({f.name, camera, segment(read_depth_png(f.depth), camera, params)});
    return out;
  }();
  return all;
}

void BM_Coplanarity(benchmark::State& state) {
  set_threads(1);
  const Frame& f = frames()[static_cast<size_t>(state.range(0))];
  const Params params;
  for (auto _ : state)
    benchmark::DoNotOptimize(coplanar_pairs(f.result.patches, {}, f.result.points, f.camera, params.coplanarity, params.seed));
  state.SetLabel(f.name + ", " + std::to_string(f.result.patches.size()) + " patches");
}

void BM_Curvature(benchmark::State& state) {
  const Frame& f = frames()[static_cast<size_t>(state.range(0))];
  const Result& r = f.result;
  const Params params;
  for (auto _ : state)
    benchmark::DoNotOptimize(curvature_links(r.patches, {}, r.core_patch_labels, r.points, r.normals, f.camera, params));
  state.SetLabel(f.name + ", " + std::to_string(r.patches.size()) + " patches");
}

void each_frame(benchmark::internal::Benchmark* b) {
  for (size_t i = 0; i < frames().size(); ++i) b->Arg(static_cast<int>(i));
}

BENCHMARK(BM_Coplanarity)->Apply(each_frame)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Curvature)->Apply(each_frame)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
