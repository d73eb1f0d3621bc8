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
};

// Stoer-Wagner global minimum cut on a dense symmetric k x k matrix (row-major, zero diagonal; it is
// consumed). Each phase is a maximum-adjacency ordering in O(n^2) over the n nodes still left: one
// pass adds the newest node's row to the keys and takes their maximum (vectorised), a second finds its
// index. Merged nodes are compacted away, so every pass runs over contiguous memory. O(k^3) in all.
DenseCut stoer_wagner(std::vector<double>& w, int k) {
  DenseCut best;
  if (k < 2) return best;
  std::vector<std::vector<int>> members(static_cast<size_t>(k));
  for (int i = 0; i < k; ++i) members[static_cast<size_t>(i)] = {i};
  std::vector<double> keys(static_cast<size_t>(k));
  const auto K = static_cast<size_t>(k);
  for (int n = k; n > 1; --n) {
    double* key = keys.data();
    std::fill(key, key + n, 0.0);
    key[0] = -kInf;  // in the ordering already; -inf stays -inf under additions
    int prev = 0, last = 0;
    double last_key = 0;
    for (int step = 1; step < n; ++step) {
      const double* row = &w[static_cast<size_t>(last) * K];
      double m = -kInf;
#pragma omp simd reduction(max : m)
      for (int j = 0; j < n; ++j) {
        key[j] += row[j];
        m = key[j] > m ? key[j] : m;
      }
      int next = 0;
      while (key[next] != m) ++next;
      prev = last;
      last = next;
      last_key = m;
      key[next] = -kInf;
    }
    // Cut of the phase: the last node (with everything merged into it) against the rest.
    if (last_key < best.cost) {
      best.cost = last_key;
      best.side = members[static_cast<size_t>(last)];
    }
    // Merge `last` into `prev`, then move the final slot into `last`'s place.
    double* rs = &w[static_cast<size_t>(prev) * K];
    const double* rt = &w[static_cast<size_t>(last) * K];
    for (int j = 0; j < n; ++j) rs[j] += rt[j];
    rs[prev] = 0;
    for (int j = 0; j < n; ++j) w[static_cast<size_t>(j) * K + static_cast<size_t>(prev)] = rs[j];
    auto& into = members[static_cast<size_t>(prev)];
    const auto& from = members[static_cast<size_t>(last)];
    into.insert(into.end(), from.begin(), from.end());
    const int end = n - 1;
    if (last != end) {
      for (int j = 0; j < n; ++j) {
        if (j == last) continue;
        w[static_cast<size_t>(last) * K + static_cast<size_t>(j)] = w[static_cast<size_t>(end) * K + static_cast<size_t>(j)];
        w[static_cast<size_t>(j) * K + static_cast<size_t>(last)] = w[static_cast<size_t>(j) * K + static_cast<size_t>(end)];
      }
      w[static_cast<size_t>(last) * K + static_cast<size_t>(last)] = 0;
      members[static_cast<size_t>(last)] = std::move(members[static_cast<size_t>(end)]);
    }
  }
  std::sort(best.side.begin(), best.side.end());
  return best;
}

int find_root(std::vector<int>& parent, int x) {
  while (parent[static_cast<size_t>(x)] != x) {
    parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
    x = parent[static_cast<size_t>(x)];
  }
  return x;
}

}  // namespace

std::vector<GraphEdge> weight_graph(int num_nodes, std::vector<GraphEdge> links) {
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
    e.weight = static_cast<float>(0.5 * (1.0 / degree[static_cast<size_t>(e.a)] + 1.0 / degree[static_cast<size_t>(e.b)]));
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
  std::vector<double> w(static_cast<size_t>(k) * static_cast<size_t>(k), 0.0);
  for (const auto& e : edges) {
    check_edge(e, std::numeric_limits<int>::max());
    if (e.a > max_node || e.b > max_node) continue;
    const int i = local[static_cast<size_t>(e.a)], j = local[static_cast<size_t>(e.b)];
    if (i < 0 || j < 0 || i == j) continue;
    w[static_cast<size_t>(i) * static_cast<size_t>(k) + static_cast<size_t>(j)] += e.weight;
    w[static_cast<size_t>(j) * static_cast<size_t>(k) + static_cast<size_t>(i)] += e.weight;
  }
  DenseCut cut = stoer_wagner(w, k);
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
  std::vector<std::vector<double>> matrices(components.size());
  for (size_t c = 0; c < components.size(); ++c)
    matrices[c].assign(components[c].size() * components[c].size(), 0.0);
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
    std::vector<double> sub;
    while (!pending.empty()) {
      std::vector<int> set = std::move(pending.back());
      pending.pop_back();
      if (set.size() == 1) {
        parts.push_back({{comp[static_cast<size_t>(set[0])]}, std::numeric_limits<float>::infinity()});
        continue;
      }
      const size_t n = set.size();
      sub.assign(n * n, 0.0);
      for (size_t x = 0; x < n; ++x)
        for (size_t y = 0; y < n; ++y) sub[x * n + y] = matrices[c][static_cast<size_t>(set[x]) * k + static_cast<size_t>(set[y])];
      const DenseCut cut = stoer_wagner(sub, static_cast<int>(n));
      if (cut.cost < theta_c - kCutEpsilon) {
        std::vector<char> on_side(n, 0);
        for (int i : cut.side) on_side[static_cast<size_t>(i)] = 1;
        std::vector<int> first, second;
        for (size_t x = 0; x < n; ++x) (on_side[x] ? first : second).push_back(set[x]);
        pending.push_back(std::move(first));
        pending.push_back(std::move(second));
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
