#include "clutterseg/graph_cut.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

namespace clutterseg {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// A cut must be cheaper than theta_c by more than the rounding of float weights: a cut that equals
// theta_c exactly (the chain a-b-c-d has w_bc = 0.5) must not split on rounding noise.
constexpr double kCutEpsilon = 1e-6;

void check_edge(const GraphEdge& e, int num_nodes) {
  if (e.a < 0 || e.b < 0 || e.a >= num_nodes || e.b >= num_nodes)
    throw Error("patch graph: edge (" + std::to_string(e.a) + ", " + std::to_string(e.b) + ") refers to a node outside 0.." +
                std::to_string(num_nodes - 1));
  if (!std::isfinite(e.weight) || e.weight < 0)
    throw Error("patch graph: edge (" + std::to_string(e.a) + ", " + std::to_string(e.b) + ") has weight " +
                std::to_string(e.weight) + ", expected finite and >= 0");
}

struct DenseCut {
  double cost = kInf;
  std::vector<int> side;  // local indices of one side
  // When stopped early: disjoint groups, each of which may be cut off from the rest (and from each
  // other) at a cost below the stop value; `side` is then the first of them.
  std::vector<std::vector<int>> cheap_groups;
};

// Global minimum cut of a dense symmetric k x k weight matrix (row-major, zero diagonal; consumed).
//
// Stoer-Wagner, accelerated by the contraction test of Nagamochi, Ono and Ibaraki: in a maximum-
// adjacency ordering, when node x is added and raises the key of a later node y to q, the two are at
// least q apart (lambda(x, y) >= q). Every such pair with q >= the best cut seen so far can be merged
// without losing a cut cheaper than that best, so one O(n^2) ordering merges many pairs at once (on
// dense graphs most of them) where plain Stoer-Wagner merges one. When no pair qualifies, the last
// two nodes of the ordering are merged as in Stoer-Wagner, so every round shrinks the graph and the
// whole stays O(k^3) in the worst case. Each node's weighted degree is itself a cut, checked every round.
// Returns as soon as a cut cheaper than `stop_below` is found: any such cut is a valid split.
// Floats: cut values carry ~1e-7 relative rounding, far below the decision margin kCutEpsilon.
DenseCut minimum_cut(std::vector<float>& w, int k, double stop_below) {
  DenseCut best;
  if (k < 2) return best;
  std::vector<std::vector<int>> members(static_cast<size_t>(k));
  for (int i = 0; i < k; ++i) members[static_cast<size_t>(i)] = {i};
  const auto K = static_cast<size_t>(k);
  std::vector<float> keys(K);
  std::vector<int> parent(K), new_index(K);
  auto record = [&](double cost, int node) {
    if (cost < best.cost) {
      best.cost = cost;
      best.side = members[static_cast<size_t>(node)];
    }
  };
  auto row_of = [&](int i) { return &w[static_cast<size_t>(i) * K]; };

  for (int n = k; n > 1;) {
    for (int i = 0; i < n; ++i) {
      const float* row = row_of(i);
      double degree = 0;
      for (int j = 0; j < n; ++j) degree += row[j];
      record(degree, i);
      // Every group whose own cut is cheap can be cut off: taking others away first only lowers it.
      if (degree < stop_below) best.cheap_groups.push_back(members[static_cast<size_t>(i)]);
    }
    if (best.cost < stop_below) break;

    // Pairs at least the best cut apart can be merged. Float sums carry ~1e-7 relative rounding: the
    // slack lets exact ties (a clique's every pair) merge, and loses at most cuts that much cheaper.
    const auto contract_at = static_cast<float>(best.cost * (1 - 1e-6));
    std::iota(parent.begin(), parent.begin() + n, 0);
    int merged = 0;
    auto unite = [&](int a, int b) {
      a = find_root(parent, a);
      b = find_root(parent, b);
      if (a != b) { parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b); ++merged; }
    };
    // Padberg-Rinaldi: the edge u-v and the two-edge paths u-z-v are edge-disjoint, so lambda(u, v) >=
    // w(u, v) + sum_z min(w(u, z), w(z, v)). Tested for each node's heaviest edge, O(n) each; this is
    // what merges dense, evenly weighted graphs (where the ordering test below finds few pairs).
    for (int u = 0; u < n; ++u) {
      const float* row = row_of(u);
      int v = 0;
      for (int j = 1; j < n; ++j) v = row[j] > row[v] ? j : v;
      if (row[v] <= 0) continue;
      const float* other = row_of(v);
      float bound = row[v];
#pragma omp simd reduction(+ : bound)
      for (int j = 0; j < n; ++j) bound += std::min(row[j], other[j]);
      if (bound >= contract_at) unite(u, v);
    }

    // One maximum-adjacency ordering from node 0; -inf keys mark the nodes already ordered.
    float* key = keys.data();
    std::fill(key, key + n, 0.f);
    int prev = 0, last = 0, x = 0;
    for (int step = 0; step < n; ++step) {
      prev = last;
      last = x;
      key[x] = -INFINITY;
      if (step == n - 1) break;
      const float* row = row_of(x);
      float m = -INFINITY;
#pragma omp simd reduction(max : m)
      for (int j = 0; j < n; ++j) {
        key[j] += row[j];
        m = key[j] > m ? key[j] : m;
      }
      if (m >= contract_at)  // some later node is now at least the best cut away from x
        for (int j = 0; j < n; ++j)
          if (row[j] > 0 && key[j] >= contract_at) unite(x, j);
      x = 0;
      while (key[x] != m) ++x;
      if (step == n - 2) record(m, x);  // cut of the phase: the last node against all others
    }
    if (best.cost < stop_below) {
      best.cheap_groups = {best.side};
      break;
    }
    if (merged == 0) unite(last, prev);

    // Contract in place. Each root is the smallest index of its set and new indices follow the roots'
    // order, so a node's new row never lies after its old one: going through old rows in ascending
    // order, every row is read before anything is written over it.
    const int m = n - merged;
    int count = 0;
    for (int i = 0; i < n; ++i) new_index[static_cast<size_t>(i)] = find_root(parent, i) == i ? count++ : -1;
    for (int i = 0; i < n; ++i) new_index[static_cast<size_t>(i)] = new_index[static_cast<size_t>(find_root(parent, i))];
    std::vector<std::vector<int>> grouped(static_cast<size_t>(m));
    for (int i = 0; i < n; ++i) {
      auto& g = grouped[static_cast<size_t>(new_index[static_cast<size_t>(i)])];
      const auto& from = members[static_cast<size_t>(i)];
      g.insert(g.end(), from.begin(), from.end());
    }
    float* merged_columns = keys.data();  // scratch; keys are reset next round
    for (int i = 0; i < n; ++i) {
      float* row = row_of(i);
      std::fill(merged_columns, merged_columns + m, 0.f);
      for (int j = 0; j < n; ++j) merged_columns[new_index[static_cast<size_t>(j)]] += row[j];
      const int r = new_index[static_cast<size_t>(i)];
      float* to = row_of(r);
      if (find_root(parent, i) == i) std::copy(merged_columns, merged_columns + m, to);
      else for (int j = 0; j < m; ++j) to[j] += merged_columns[j];
    }
    for (int i = 0; i < m; ++i) row_of(i)[i] = 0;
    for (int i = 0; i < m; ++i) members[static_cast<size_t>(i)] = std::move(grouped[static_cast<size_t>(i)]);
    n = m;
  }
  std::sort(best.side.begin(), best.side.end());
  return best;
}

}  // namespace

std::vector<GraphEdge> weight_graph(int num_nodes, std::vector<GraphEdge> links, double concave_weight) {
  for (auto& e : links) {
    if (e.a > e.b) std::swap(e.a, e.b);
    if (e.a < 0 || e.b >= num_nodes || e.a == e.b)
      throw Error("patch graph: link (" + std::to_string(e.a) + ", " + std::to_string(e.b) + ") is not between two of " +
                  std::to_string(num_nodes) + " nodes");
  }
  // Stable, so that the first link of a pair (the earliest cue) is the one kept.
  std::stable_sort(links.begin(), links.end(), [](const GraphEdge& x, const GraphEdge& y) {
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  links.erase(std::unique(links.begin(), links.end(), [](const GraphEdge& x, const GraphEdge& y) {
    return x.a == y.a && x.b == y.b;
  }), links.end());
  std::vector<int> degree(static_cast<size_t>(std::max(0, num_nodes)), 0);
  for (const auto& e : links) { ++degree[static_cast<size_t>(e.a)]; ++degree[static_cast<size_t>(e.b)]; }
  // w_ij = 1/deg(i) out of i, 1/deg(j) out of j; W_sym = (W + W^T)/2 (paper i).
  for (auto& e : links)
    e.weight = static_cast<float>(0.5 * (1.0 / degree[static_cast<size_t>(e.a)] + 1.0 / degree[static_cast<size_t>(e.b)]) *
                                  (e.cue == Cue::AdjacentConcave ? concave_weight : 1.0));
  return links;
}

std::pair<double, std::vector<int>> min_cut(const std::vector<int>& nodes, const std::vector<GraphEdge>& edges) {
  if (nodes.size() < 2) return {kInf, {}};
  const int max_node = *std::max_element(nodes.begin(), nodes.end());
  if (*std::min_element(nodes.begin(), nodes.end()) < 0) throw Error("min_cut: negative node index");
  std::vector<int> local(static_cast<size_t>(max_node) + 1, -1);
  for (size_t i = 0; i < nodes.size(); ++i) {
    auto& l = local[static_cast<size_t>(nodes[i])];
    if (l >= 0) throw Error("min_cut: node " + std::to_string(nodes[i]) + " listed twice");
    l = static_cast<int>(i);
  }
  const int k = static_cast<int>(nodes.size());
  std::vector<float> w(static_cast<size_t>(k) * static_cast<size_t>(k), 0.f);
  for (const auto& e : edges) {
    check_edge(e, std::numeric_limits<int>::max());
    if (e.a > max_node || e.b > max_node) continue;
    const int i = local[static_cast<size_t>(e.a)], j = local[static_cast<size_t>(e.b)];
    if (i < 0 || j < 0 || i == j) continue;
    w[static_cast<size_t>(i) * static_cast<size_t>(k) + static_cast<size_t>(j)] += e.weight;
    w[static_cast<size_t>(j) * static_cast<size_t>(k) + static_cast<size_t>(i)] += e.weight;
  }
  DenseCut cut = minimum_cut(w, k, -kInf);
  std::vector<int> side;
  side.reserve(cut.side.size());
  for (int i : cut.side) side.push_back(nodes[static_cast<size_t>(i)]);
  std::sort(side.begin(), side.end());
  return {cut.cost, side};
}

Partition cut_graph(int num_nodes, const std::vector<GraphEdge>& edges, double theta_c) {
  Partition out;
  if (num_nodes <= 0) return out;
  for (const auto& e : edges) check_edge(e, num_nodes);

  // Connected components; each gets its own dense weight matrix.
  std::vector<int> parent(static_cast<size_t>(num_nodes));
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& e : edges) parent[static_cast<size_t>(find_root(parent, e.a))] = find_root(parent, e.b);
  std::vector<int> component_of(static_cast<size_t>(num_nodes), -1), local(static_cast<size_t>(num_nodes));
  std::vector<std::vector<int>> components;
  for (int v = 0; v < num_nodes; ++v) {
    const int root = find_root(parent, v);
    auto& c = component_of[static_cast<size_t>(root)];
    if (c < 0) { c = static_cast<int>(components.size()); components.emplace_back(); }
    component_of[static_cast<size_t>(v)] = c;
    local[static_cast<size_t>(v)] = static_cast<int>(components[static_cast<size_t>(c)].size());
    components[static_cast<size_t>(c)].push_back(v);
  }
  std::vector<std::vector<float>> matrices(components.size());
  for (size_t c = 0; c < components.size(); ++c)
    matrices[c].assign(components[c].size() * components[c].size(), 0.f);
  for (const auto& e : edges) {
    if (e.a == e.b) continue;
    const auto c = static_cast<size_t>(component_of[static_cast<size_t>(e.a)]);
    const auto k = components[c].size();
    const auto i = static_cast<size_t>(local[static_cast<size_t>(e.a)]), j = static_cast<size_t>(local[static_cast<size_t>(e.b)]);
    matrices[c][i * k + j] += e.weight;
    matrices[c][j * k + i] += e.weight;
  }

  // Split recursively at the global minimum cut while it is cheaper than theta_c. The final parts do
  // not depend on which of several cheap cuts is taken first (see docs/COMPOSITION.md), and there are
  // at most V - 1 splits, so the whole is O(V^4) in the worst case and O(V^3) when nothing splits.
  struct Part {
    std::vector<int> nodes;  // global node ids, ascending
    float cost;
  };
  std::vector<Part> parts;
  for (size_t c = 0; c < components.size(); ++c) {
    const auto& comp = components[c];
    const size_t k = comp.size();
    std::vector<std::vector<int>> pending{std::vector<int>(k)};
    std::iota(pending.back().begin(), pending.back().end(), 0);
    std::vector<float> sub;
    while (!pending.empty()) {
      std::vector<int> set = std::move(pending.back());
      pending.pop_back();
      if (set.size() == 1) {
        parts.push_back({{comp[static_cast<size_t>(set[0])]}, std::numeric_limits<float>::infinity()});
        continue;
      }
      const size_t n = set.size();
      sub.assign(n * n, 0.f);
      for (size_t x = 0; x < n; ++x)
        for (size_t y = 0; y < n; ++y) sub[x * n + y] = matrices[c][static_cast<size_t>(set[x]) * k + static_cast<size_t>(set[y])];
      const DenseCut cut = minimum_cut(sub, static_cast<int>(n), theta_c - kCutEpsilon);
      if (cut.cost < theta_c - kCutEpsilon) {
        std::vector<int> group_of(n, 0);  // 0 = the rest
        for (size_t g = 0; g < cut.cheap_groups.size(); ++g)
          for (int i : cut.cheap_groups[g]) group_of[static_cast<size_t>(i)] = static_cast<int>(g) + 1;
        std::vector<std::vector<int>> split(cut.cheap_groups.size() + 1);
        for (size_t x = 0; x < n; ++x) split[static_cast<size_t>(group_of[x])].push_back(set[x]);
        for (auto& part : split)
          if (!part.empty()) pending.push_back(std::move(part));
      } else {
        Part part{{}, static_cast<float>(cut.cost)};
        for (int i : set) part.nodes.push_back(comp[static_cast<size_t>(i)]);
        std::sort(part.nodes.begin(), part.nodes.end());
        parts.push_back(std::move(part));
      }
    }
  }

  // Objects numbered by their smallest node, so the numbering depends only on the partition.
  std::sort(parts.begin(), parts.end(), [](const Part& x, const Part& y) { return x.nodes.front() < y.nodes.front(); });
  out.object_of_node.assign(static_cast<size_t>(num_nodes), -1);
  for (size_t o = 0; o < parts.size(); ++o) {
    for (int v : parts[o].nodes) out.object_of_node[static_cast<size_t>(v)] = static_cast<int>(o);
    out.cut_cost.push_back(parts[o].cost);
  }
  return out;
}

}  // namespace clutterseg
