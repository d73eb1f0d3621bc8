// Paper i): probabilistic object composition on the patch graph.
#pragma once

#include "clutterseg/types.hpp"

namespace clutterseg {

// Weights w_ij = 1/deg(i) for every link, symmetrised W = (W + W^T) / 2, and multiplied by
// concave_weight for links of cue AdjacentConcave (beyond the paper: the evidence that two patches
// meet as two objects do). Duplicate links between the same pair keep the first cue. Returned edges
// have a < b, sorted.
std::vector<GraphEdge> weight_graph(int num_nodes, std::vector<GraphEdge> links, double concave_weight = 1);

struct Partition {
  std::vector<int> object_of_node;  // 0-based object index per node
  std::vector<float> cut_cost;      // per object: its cheapest cut (global min cut); +inf if one node
};

// Splits every connected component recursively at its global minimum cut (Stoer-Wagner) while that
// cut costs less than theta_c. O(V^3) per split, at most V splits: bounded on any graph.
Partition cut_graph(int num_nodes, const std::vector<GraphEdge>& edges, double theta_c);

// Global minimum cut of the subgraph induced by `nodes` (Stoer-Wagner); returns cost and one side.
std::pair<double, std::vector<int>> min_cut(const std::vector<int>& nodes,
                                            const std::vector<GraphEdge>& edges);

}  // namespace clutterseg
