// The tracker alone (Tracker::update: overlap, matching, relabelling the 640x480 label image), on the
// objects clutterseg finds in real 640x480 frames: ycbv-0000 (one scene, a moving camera) and osd-kinect
// (unrelated scenes: every frame mostly new objects, the most matching work). One core. Run:
//   ./build/bench/bench_tracking --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>

#include "clutterseg/io.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/tracking.hpp"

using namespace clutterseg;

namespace {

struct Segmented {
  cv::Mat labels;               // objects 1..M, as the pipeline makes them
  std::vector<Object> objects;  // objects[i].id == i + 1
};

// Every frame of a dev set segmented once, without tracking, in name order.
const std::vector<Segmented>& frames(const std::string& set) {
  static std::map<std::string, std::vector<Segmented>> cache;
  auto it = cache.find(set);
  if (it != cache.end()) return it->second;
  const std::filesystem::path dir = std::filesystem::path(CLUTTERSEG_DATA_DIR) / set;
  const Camera camera = read_camera_json(dir / "camera.json");
  Params params;
  params.tracking.enabled = false;
  Segmenter segmenter(params);
  std::vector<Segmented> out;
  for (const auto& f : list_dataset(dir)) {
    Result r = segmenter.segment(read_depth_png(f.depth), camera);
    out.push_back({r.object_labels, r.objects});
  }
  return cache[set] = out;
}

void BM_TrackerUpdate(benchmark::State& state, const std::string& set) {
  set_threads(1);
  const auto& input = frames(set);
  Tracker tracker;
  std::vector<Segmented> work(input.size());
  size_t objects = 0;
  for (const auto& f : input) objects += f.objects.size();
  for (auto _ : state) {
    state.PauseTiming();  // fresh copies: the tracker rewrites labels and objects in place
    tracker.reset();
    for (size_t i = 0; i < input.size(); ++i) {
      input[i].labels.copyTo(work[i].labels);
      work[i].objects = input[i].objects;
    }
    state.ResumeTiming();
    for (auto& f : work) benchmark::DoNotOptimize(tracker.update(f.labels, f.objects));
  }
  state.counters["per_frame"] = benchmark::Counter(static_cast<double>(state.iterations() * input.size()),
                                                   benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["objects_per_frame"] = static_cast<double>(objects) / static_cast<double>(input.size());
}

BENCHMARK_CAPTURE(BM_TrackerUpdate, ycbv_0000, std::string("ycbv-0000"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_TrackerUpdate, osd_kinect, std::string("osd-kinect"))->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
