// Paper i): 1/deg weights and recursive minimum cuts on the patch graph.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <random>

#include "clutterseg/graph_cut.hpp"

using namespace clutterseg;

namespace {

std::vector<GraphEdge> links(const std::vector<std::pair<int, int>>& pairs, Cue cue = Cue::Adjacent) {
  std::vector<GraphEdge> out;
  for (auto [a, b] : pairs) out.push_back({a, b, cue, 0.f});
  return out;
}

// Canonical form of a partition: each node's object renamed by the first node of that object.
std::vector<int> canonical(const std::vector<int>& object_of_node) {
  std::vector<int> first(object_of_node.size(), -1), out(object_of_node.size());
  for (size_t v = 0; v < object_of_node.size(); ++v) {
    auto& f = first[static_cast<size_t>(object_of_node[v])];
    if (f < 0) f = static_cast<int>(v);
    out[v] = f;
  }
  return out;
}

// Cost of the cut between `in` (bitmask over `nodes`) and the rest of `nodes`.
double cut_cost(const std::vector<int>& nodes, unsigned in, const std::vector<GraphEdge>& edges) {
  std::vector<int> side(64, -1);
  for (size_t i = 0; i < nodes.size(); ++i) side[static_cast<size_t>(nodes[i])] = (in >> i) & 1u;
  double cost = 0;
  for (const auto& e : edges) {
    const int sa = side[static_cast<size_t>(e.a)], sb = side[static_cast<size_t>(e.b)];
    if (sa >= 0 && sb >= 0 && sa != sb) cost += e.weight;
  }
  return cost;
}

// Brute force: the cheapest of all 2^(n-1) - 1 bipartitions of `nodes`.
std::pair<double, unsigned> brute_min_cut(const std::vector<int>& nodes, const std::vector<GraphEdge>& edges) {
  double best = INFINITY;
  unsigned best_mask = 0;
  const unsigned n = static_cast<unsigned>(nodes.size());
  for (unsigned mask = 1; mask < (1u << (n - 1)); ++mask) {  // node n-1 always outside: each cut once
    const double c = cut_cost(nodes, mask, edges);
    if (c < best) { best = c; best_mask = mask; }
  }
  return {best, best_mask};
}

// Brute-force composition: split any part that has a cut cheaper than theta_c, until none has.
std::vector<int> brute_partition(int num_nodes, const std::vector<GraphEdge>& edges, double theta_c) {
  std::vector<int> object(static_cast<size_t>(num_nodes), 0);
  int objects = 1;
  for (bool split = true; split;) {
    split = false;
    for (int o = 0; o < objects && !split; ++o) {
      std::vector<int> nodes;
      for (int v = 0; v < num_nodes; ++v)
        if (object[static_cast<size_t>(v)] == o) nodes.push_back(v);
      if (nodes.size() < 2) continue;
      const auto [cost, mask] = brute_min_cut(nodes, edges);
      if (cost < theta_c - 1e-6) {
        for (size_t i = 0; i < nodes.size(); ++i)
          if ((mask >> i) & 1u) object[static_cast<size_t>(nodes[i])] = objects;
        ++objects;
        split = true;
      }
    }
  }
  return object;
}

}  // namespace

TEST(WeightGraph, OneOverDegreeSymmetrised) {
  // Star: the centre has degree 3, the leaves degree 1: w = (1/3 + 1) / 2.
  const auto w = weight_graph(4, links({{0, 1}, {2, 0}, {0, 3}}));
  ASSERT_EQ(w.size(), 3u);
  for (const auto& e : w) {
    EXPECT_EQ(e.a, 0);
    EXPECT_FLOAT_EQ(e.weight, (1.f / 3 + 1.f) / 2);
  }
  EXPECT_EQ(w[1].b, 2);  // normalised to a < b and sorted
}

TEST(WeightGraph, DuplicateLinksKeepTheFirstCueAndCountOnce) {
  auto l = links({{0, 1}, {1, 2}});
  l.push_back({1, 0, Cue::Coplanar, 0.f});
  const auto w = weight_graph(3, l);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(w[0].cue, Cue::Adjacent);
  EXPECT_FLOAT_EQ(w[0].weight, (1.f + 0.5f) / 2);  // node 1 has degree 2, not 3
}

TEST(WeightGraph, RejectsLinksOutsideTheGraph) {
  EXPECT_THROW(weight_graph(3, links({{0, 3}})), Error);
  EXPECT_THROW(weight_graph(3, links({{1, 1}})), Error);
  EXPECT_THROW(cut_graph(3, {{0, 5, Cue::Adjacent, 1.f}}, 0.5), Error);
  EXPECT_THROW(cut_graph(3, {{0, 1, Cue::Adjacent, -1.f}}, 0.5), Error);
}

TEST(GraphCut, TwoTrianglesJoinedByOneEdgeSplit) {
  const auto w = weight_graph(6, links({{0, 1}, {1, 2}, {0, 2}, {3, 4}, {4, 5}, {3, 5}, {2, 3}}));
  const Partition p = cut_graph(6, w, 0.5);
  EXPECT_EQ(canonical(p.object_of_node), (std::vector<int>{0, 0, 0, 3, 3, 3}));
  ASSERT_EQ(p.cut_cost.size(), 2u);
  // Each triangle's cheapest cut isolates its bridge node: (1/2 + 1/3) / 2 twice.
  EXPECT_NEAR(p.cut_cost[0], 2 * (0.5 + 1.0 / 3) / 2, 1e-6);
  // The bridge alone costs (1/3 + 1/3) / 2 < 0.5; a threshold below it keeps the pair whole.
  EXPECT_EQ(cut_graph(6, w, 0.3).cut_cost.size(), 1u);
}

TEST(GraphCut, ChainSplitsOnlyBelowTheThreshold) {
  // Chain 0-1-2-3-4: end links weigh (1 + 1/2)/2 = 0.75, inner links exactly 0.5.
  const auto w = weight_graph(5, links({{0, 1}, {1, 2}, {2, 3}, {3, 4}}));
  const Partition whole = cut_graph(5, w, 0.5);  // 0.5 is not cheaper than 0.5
  EXPECT_EQ(whole.cut_cost.size(), 1u);
  EXPECT_NEAR(whole.cut_cost[0], 0.5, 1e-6);
  const Partition split = cut_graph(5, w, 0.6);
  EXPECT_EQ(canonical(split.object_of_node), (std::vector<int>{0, 0, 2, 3, 3}));
  EXPECT_EQ(split.cut_cost[1], INFINITY);  // the lone middle node
}

TEST(GraphCut, DenseCliqueStaysWhole) {
  std::vector<std::pair<int, int>> pairs;
  const int n = 40;
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) pairs.emplace_back(a, b);
  const Partition p = cut_graph(n, weight_graph(n, links(pairs)), 0.5);
  ASSERT_EQ(p.cut_cost.size(), 1u);
  EXPECT_NEAR(p.cut_cost[0], 1.0, 1e-5);  // one node's n-1 links of 1/(n-1) each
}

TEST(GraphCut, IsolatedNodesAreObjectsOfTheirOwn) {
  const Partition p = cut_graph(4, weight_graph(4, links({{1, 2}})), 0.5);
  EXPECT_EQ(canonical(p.object_of_node), (std::vector<int>{0, 1, 1, 3}));
  EXPECT_EQ(p.cut_cost[0], INFINITY);
  EXPECT_NEAR(p.cut_cost[1], 1.0, 1e-6);
  EXPECT_TRUE(cut_graph(0, {}, 0.5).object_of_node.empty());
}

TEST(GraphCut, IndependentOfEdgeOrder) {
  std::mt19937_64 rng(7);
  std::vector<std::pair<int, int>> pairs;
  for (int a = 0; a < 30; ++a)
    for (int b = a + 1; b < 30; ++b)
      if (rng() % 5 == 0) pairs.emplace_back(a, b);
  const auto w = weight_graph(30, links(pairs));
  const Partition first = cut_graph(30, w, 0.5);
  auto shuffled = w;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  const Partition second = cut_graph(30, shuffled, 0.5);
  EXPECT_EQ(first.object_of_node, second.object_of_node);
  EXPECT_EQ(first.cut_cost, second.cut_cost);
  EXPECT_EQ(cut_graph(30, w, 0.5).object_of_node, first.object_of_node);
}

TEST(GraphCut, SameDecisionsAsBruteForceOnSmallRandomGraphs) {
  std::mt19937_64 rng(2013);
  int splits_seen = 0, wholes_seen = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 11);  // 2..12 nodes
    const double density = 0.2 + 0.7 * static_cast<double>(rng() % 1000) / 1000;
    std::vector<std::pair<int, int>> pairs;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        if (static_cast<double>(rng() % 1000) / 1000 < density) pairs.emplace_back(a, b);
    if (pairs.empty()) continue;
    auto w = weight_graph(n, links(pairs));
    if (trial % 2) // also arbitrary weights, not only 1/deg ones
      for (auto& e : w) e.weight = static_cast<float>(rng() % 1000) / 1000.f;
    const double theta = std::array{0.3, 0.5, 0.8}[trial % 3];

    const Partition p = cut_graph(n, w, theta);
    EXPECT_EQ(canonical(p.object_of_node), canonical(brute_partition(n, w, theta))) << "trial " << trial;
    // Each object's reported cost is its brute-force minimum cut, and not below theta.
    for (size_t o = 0; o < p.cut_cost.size(); ++o) {
      std::vector<int> nodes;
      for (int v = 0; v < n; ++v)
        if (p.object_of_node[static_cast<size_t>(v)] == static_cast<int>(o)) nodes.push_back(v);
      if (nodes.size() == 1) { EXPECT_EQ(p.cut_cost[o], INFINITY); continue; }
      const double brute = brute_min_cut(nodes, w).first;
      EXPECT_NEAR(p.cut_cost[o], brute, 1e-5) << "trial " << trial;
      EXPECT_GE(brute, theta - 1e-6);
    }
    (p.cut_cost.size() > 1 ? splits_seen : wholes_seen)++;
  }
  EXPECT_GT(splits_seen, 50);  // both outcomes were exercised
  EXPECT_GT(wholes_seen, 50);
}

TEST(MinCut, EqualsBruteForceAndReturnsASideOfThatCost) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 120; ++trial) {
    const int n = 2 + static_cast<int>(rng() % 15);  // 2..16 nodes
    std::vector<GraphEdge> edges;
    for (int a = 0; a < n; ++a)
      for (int b = a + 1; b < n; ++b)
        if (rng() % 3 != 0) edges.push_back({a, b, Cue::Adjacent, static_cast<float>(1 + rng() % 1000) / 1000.f});
    if (trial % 3 == 0) {  // evenly weighted cliques: every pair ties
      edges.clear();
      for (int a = 0; a < n; ++a)
        for (int b = a + 1; b < n; ++b) edges.push_back({a, b, Cue::Adjacent, 1.f / static_cast<float>(n - 1)});
    }
    std::vector<int> nodes(static_cast<size_t>(n));
    std::iota(nodes.begin(), nodes.end(), 0);
    const auto [cost, side] = min_cut(nodes, edges);
    EXPECT_NEAR(cost, brute_min_cut(nodes, edges).first, 1e-5) << "trial " << trial;
    ASSERT_FALSE(side.empty());
    ASSERT_LT(side.size(), nodes.size());
    unsigned mask = 0;
    for (int v : side) mask |= 1u << v;
    EXPECT_NEAR(cut_cost(nodes, mask, edges), cost, 1e-5) << "trial " << trial;
  }
}

TEST(MinCut, FindsTheLightestCutOfASubgraph) {
  // Square 0-1-2-3 with a heavy diagonal 0-2 and a light side 2-3 / 3-0: node 3 is cut off.
  const std::vector<GraphEdge> e = {{0, 1, Cue::Adjacent, 1.f}, {1, 2, Cue::Adjacent, 1.f}, {2, 3, Cue::Adjacent, 0.2f},
                                    {0, 3, Cue::Adjacent, 0.1f}, {0, 2, Cue::Adjacent, 2.f}, {3, 4, Cue::Adjacent, 5.f}};
  const auto [cost, side] = min_cut({0, 1, 2, 3}, e);  // node 4 is outside the subgraph: ignored
  EXPECT_NEAR(cost, 0.3, 1e-6);
  EXPECT_EQ(side, std::vector<int>{3});
  EXPECT_EQ(min_cut({2}, e).first, INFINITY);
  EXPECT_THROW(min_cut({1, 1}, e), Error);
}

TEST(GraphCut, HundredsOfDenselyLinkedPatchesSplitIntoTheirClusters) {
  // 30 dense clusters of 10 patches, neighbouring clusters joined by one link: every cluster is found.
  std::mt19937_64 rng(5);
  std::vector<std::pair<int, int>> pairs;
  const int clusters = 30, size = 10, n = clusters * size;
  for (int c = 0; c < clusters; ++c) {
    for (int a = 0; a < size; ++a)
      for (int b = a + 1; b < size; ++b)
        if (rng() % 4 != 0) pairs.emplace_back(c * size + a, c * size + b);
    if (c + 1 < clusters) pairs.emplace_back(c * size + static_cast<int>(rng() % size), (c + 1) * size + static_cast<int>(rng() % size));
  }
  const Partition p = cut_graph(n, weight_graph(n, links(pairs)), 0.5);
  EXPECT_EQ(p.cut_cost.size(), static_cast<size_t>(clusters));
  for (int v = 0; v < n; ++v) EXPECT_EQ(p.object_of_node[static_cast<size_t>(v)], v / size);
}
