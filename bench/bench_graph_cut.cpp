// Paper i) on large patch graphs: the recursive minimum cut must stay within a frame's budget.
//   ./build/bench/bench_graph_cut --benchmark_min_time=0.5s
#include <benchmark/benchmark.h>

#include <random>

#include "clutterseg/graph_cut.hpp"

using namespace clutterseg;

namespace {

// Every pair linked with probability `density` (percent), 1/deg weights.
std::vector<GraphEdge> random_graph(int n, int density, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<GraphEdge> links;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b)
      if (static_cast<int>(rng() % 100) < density) links.push_back({a, b, Cue::Adjacent, 0.f});
  return weight_graph(n, links);
}

// Dense clusters of `size` patches in a chain, one link between neighbouring clusters: one split per
// cluster, the worst case for recursive splitting.
std::vector<GraphEdge> clustered_graph(int n, int size, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<GraphEdge> links;
  for (int c = 0; c * size < n; ++c) {
    const int lo = c * size, hi = std::min(n, lo + size);
    for (int a = lo; a < hi; ++a)
      for (int b = a + 1; b < hi; ++b)
        if (rng() % 4 != 0) links.push_back({a, b, Cue::Adjacent, 0.f});
    if (hi < n) links.push_back({lo + static_cast<int>(rng() % size), hi + static_cast<int>(rng() % size), Cue::Adjacent, 0.f});
  }
  return weight_graph(n, links);
}

void BM_DenseRandomGraph(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto edges = random_graph(n, static_cast<int>(state.range(1)), 1);
  size_t objects = 0;
  for (auto _ : state) {
    const Partition p = cut_graph(n, edges, 0.5);
    objects = p.cut_cost.size();
    benchmark::DoNotOptimize(p);
  }
  state.counters["edges"] = static_cast<double>(edges.size());
  state.counters["objects"] = static_cast<double>(objects);
}
BENCHMARK(BM_DenseRandomGraph)->Args({100, 50})->Args({300, 50})->Args({300, 100})->Unit(benchmark::kMillisecond);

void BM_ClusteredGraph(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto edges = clustered_graph(n, static_cast<int>(state.range(1)), 1);
  size_t objects = 0;
  for (auto _ : state) {
    const Partition p = cut_graph(n, edges, 0.5);
    objects = p.cut_cost.size();
    benchmark::DoNotOptimize(p);
  }
  state.counters["objects"] = static_cast<double>(objects);
}
BENCHMARK(BM_ClusteredGraph)->Args({100, 10})->Args({300, 10})->Args({300, 30})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
