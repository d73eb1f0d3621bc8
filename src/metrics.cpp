#include "clutterseg/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

namespace clutterseg {

namespace {

cv::Mat as_labels(const cv::Mat& image, const char* what) {
  if (image.empty()) throw Error(std::string(what) + ": empty label image");
  if (image.channels() != 1) throw Error(std::string(what) + ": label image must have one channel");
  if (image.depth() == CV_32S) return image;
  if (image.depth() != CV_16U && image.depth() != CV_8U)
    throw Error(std::string(what) + ": label image must hold integer ids (uint8, uint16 or int32)");
  cv::Mat out;
  image.convertTo(out, CV_32S);
  return out;
}

// The ids != 0 of a label image, in increasing order, with their pixel counts and bounding boxes.
struct Objects {
  std::vector<int> ids;
  std::vector<long> area;
  std::vector<cv::Rect> bbox;
  std::unordered_map<int, int> index;  // id -> position in ids
};

Objects collect_objects(const cv::Mat& labels) {
  std::map<int, std::pair<long, cv::Rect>> found;
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (row[x] == 0) continue;
      auto [it, inserted] = found.try_emplace(row[x], 0, cv::Rect(x, y, 1, 1));
      ++it->second.first;
      it->second.second |= cv::Rect(x, y, 1, 1);
    }
  }
  Objects o;
  for (const auto& [id, stats] : found) {
    o.index[id] = static_cast<int>(o.ids.size());
    o.ids.push_back(id);
    o.area.push_back(stats.first);
    o.bbox.push_back(stats.second);
  }
  return o;
}

// a / b, with `empty` when there is nothing to divide by.
double ratio(double a, double b, double empty) { return b > 0 ? a / b : empty; }
double harmonic(double p, double r) { return p + r > 0 ? 2 * p * r / (p + r) : 0.0; }


}  // namespace

std::array<double, 10> score_values(const FrameScores& s) {
  return {s.tp, s.fp, s.fn, s.overlap_p, s.overlap_r, s.overlap_f, s.boundary_p, s.boundary_r, s.boundary_f, s.detected_75};
}

int boundary_tolerance_px(cv::Size size) {
  return static_cast<int>(std::ceil(0.003 * std::hypot(double(size.width), double(size.height))));
}

cv::Mat object_boundaries(const cv::Mat& labels_in) {
  const cv::Mat labels = as_labels(labels_in, "labels");
  cv::Mat out(labels.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    const int* up = y > 0 ? labels.ptr<int>(y - 1) : nullptr;
    const int* down = y + 1 < labels.rows ? labels.ptr<int>(y + 1) : nullptr;
    uchar* o = out.ptr<uchar>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int id = row[x];
      if (id == 0) continue;
      const bool edge = (x > 0 && row[x - 1] != id) || (x + 1 < labels.cols && row[x + 1] != id) ||
                        (up && up[x] != id) || (down && down[x] != id);
      if (edge) o[x] = 255;
    }
  }
  return out;
}

std::vector<int> max_weight_assignment(const std::vector<std::vector<double>>& weight) {
  const int rows = static_cast<int>(weight.size());
  if (rows == 0) return {};
  const int cols = static_cast<int>(weight[0].size());
  for (const auto& row : weight) {
    if (static_cast<int>(row.size()) != cols) throw Error("assignment: rows of the weight matrix differ in length");
    for (double w : row)
      if (!std::isfinite(w)) throw Error("assignment: weights must be finite");
  }
  if (cols == 0) return std::vector<int>(rows, -1);
  if (rows > cols) {
    // Solve the transpose (every column gets a row), then read it back per row.
    std::vector<std::vector<double>> t(cols, std::vector<double>(rows));
    for (int r = 0; r < rows; ++r)
      for (int c = 0; c < cols; ++c) t[c][r] = weight[r][c];
    const std::vector<int> col_to_row = max_weight_assignment(t);
    std::vector<int> row_to_col(rows, -1);
    for (int c = 0; c < cols; ++c) row_to_col[col_to_row[c]] = c;
    return row_to_col;
  }
  // Shortest augmenting paths with dual potentials u (rows), v (columns) on cost = -weight.
  // Index 0 is a virtual column that starts each augmentation; rows and columns are 1-based here.
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(rows + 1, 0), v(cols + 1, 0);
  std::vector<int> owner(cols + 1, 0), previous(cols + 1, 0);  // owner[c] = row assigned to column c
  for (int r = 1; r <= rows; ++r) {
    owner[0] = r;
    int col = 0;
    std::vector<double> slack(cols + 1, inf);
    std::vector<char> visited(cols + 1, 0);
    // Each step visits one new column, so this ends after at most cols + 1 steps.
    for (int step = 0; step <= cols && owner[col] != 0; ++step) {
      visited[col] = 1;
      const int row = owner[col];
      double delta = inf;
      int next = 0;
      for (int c = 1; c <= cols; ++c) {
        if (visited[c]) continue;
        const double reduced = -weight[row - 1][c - 1] - u[row] - v[c];
        if (reduced < slack[c]) {
          slack[c] = reduced;
          previous[c] = col;
        }
        if (slack[c] < delta) {
          delta = slack[c];
          next = c;
        }
      }
      for (int c = 0; c <= cols; ++c) {
        if (visited[c]) {
          u[owner[c]] += delta;
          v[c] -= delta;
        } else {
          slack[c] -= delta;
        }
      }
      col = next;
    }
    // Flip the alternating path back to the virtual column.
    while (col != 0) {
      const int back = previous[col];
      owner[col] = owner[back];
      col = back;
    }
  }
  std::vector<int> row_to_col(rows, -1);
  for (int c = 1; c <= cols; ++c)
    if (owner[c] > 0) row_to_col[owner[c] - 1] = c - 1;
  return row_to_col;
}

namespace {

// One nonzero cell of the contingency table: |R_i & S_j| > 0 (indices into the Objects).
struct Overlap {
  int i, j;
  double pixels;
};

// The nonzero cells of the contingency table in (i, j) order, from one pass over the pixels: runs of
// one pair are counted together, then the runs are sorted and merged. O(pixels + runs log runs),
// whatever the number of ids (a dense n x m table took 65535 x 65535 cells for 65535 ids).
std::vector<Overlap> overlaps(const cv::Mat& gt, const cv::Mat& pred, const Objects& g, const Objects& p) {
  std::vector<std::pair<std::uint64_t, long>> runs;
  for (int y = 0; y < gt.rows; ++y) {
    const int* gr = gt.ptr<int>(y);
    const int* pr = pred.ptr<int>(y);
    std::uint64_t last = ~std::uint64_t{0};
    for (int x = 0; x < gt.cols; ++x) {
      if (gr[x] == 0 || pr[x] == 0) continue;
      const std::uint64_t key = std::uint64_t(std::uint32_t(gr[x])) << 32 | std::uint32_t(pr[x]);
      if (key == last) {
        ++runs.back().second;
      } else {
        runs.emplace_back(key, 1);
        last = key;
      }
    }
  }
  std::sort(runs.begin(), runs.end());
  std::vector<Overlap> out;
  for (size_t k = 0; k < runs.size();) {
    long sum = 0;
    size_t e = k;
    for (; e < runs.size() && runs[e].first == runs[k].first; ++e) sum += runs[e].second;
    const int gid = static_cast<int>(std::uint32_t(runs[k].first >> 32)), pid = static_cast<int>(std::uint32_t(runs[k].first));
    out.push_back({g.index.at(gid), p.index.at(pid), double(sum)});
    k = e;
  }
  // Ids compare as signed ints in the Objects, as unsigned in the keys: order by index.
  std::sort(out.begin(), out.end(), [](const Overlap& a, const Overlap& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  return out;
}

// Maximum-weight one-to-one matching over the overlapping pairs only (a pair without overlap scores 0
// and is never counted). The pairs fall apart into connected components, each solved alone: exactly
// (Hungarian on the component's rows x columns) while that costs at most kExactWork steps, greedily
// (heaviest pair first) beyond, which no real frame reaches. Returns, per ground-truth object, the
// matched prediction or -1. Bounded by the pixels: at most one pair per pixel.
std::vector<int> match_overlaps(int n, int m, const std::vector<Overlap>& pairs, const std::vector<double>& weight) {
  constexpr double kExactWork = 2e8;
  std::vector<int> parent(static_cast<size_t>(n + m));
  for (size_t k = 0; k < parent.size(); ++k) parent[k] = static_cast<int>(k);
  const auto find = [&](int v) {
    while (parent[static_cast<size_t>(v)] != v) v = parent[static_cast<size_t>(v)] = parent[static_cast<size_t>(parent[static_cast<size_t>(v)])];
    return v;
  };
  for (const Overlap& o : pairs) parent[static_cast<size_t>(find(o.i))] = find(n + o.j);
  std::unordered_map<int, std::vector<size_t>> component;  // root -> its pairs
  for (size_t k = 0; k < pairs.size(); ++k) component[find(pairs[k].i)].push_back(k);
  std::vector<int> roots;
  for (const auto& [root, list] : component) roots.push_back(root);
  std::sort(roots.begin(), roots.end());  // the same order on every run

  std::vector<int> match(static_cast<size_t>(n), -1);
  std::vector<int> row_of(static_cast<size_t>(n), -1), col_of(static_cast<size_t>(m), -1);
  for (int root : roots) {
    const std::vector<size_t>& list = component[root];
    std::vector<int> rows, cols;
    for (size_t k : list) {
      const Overlap& o = pairs[k];
      if (row_of[static_cast<size_t>(o.i)] < 0) { row_of[static_cast<size_t>(o.i)] = static_cast<int>(rows.size()); rows.push_back(o.i); }
      if (col_of[static_cast<size_t>(o.j)] < 0) { col_of[static_cast<size_t>(o.j)] = static_cast<int>(cols.size()); cols.push_back(o.j); }
    }
    const double r = double(rows.size()), c = double(cols.size());
    if (std::min(r, c) * std::min(r, c) * std::max(r, c) <= kExactWork && r * c <= double(1 << 24)) {
      std::vector<std::vector<double>> w(rows.size(), std::vector<double>(cols.size(), 0.0));
      for (size_t k : list) w[static_cast<size_t>(row_of[static_cast<size_t>(pairs[k].i)])][static_cast<size_t>(col_of[static_cast<size_t>(pairs[k].j)])] = weight[k];
      const std::vector<int> assigned = max_weight_assignment(w);
      for (size_t a = 0; a < rows.size(); ++a)
        if (assigned[a] >= 0) match[static_cast<size_t>(rows[a])] = cols[static_cast<size_t>(assigned[a])];
    } else {
      std::vector<size_t> order = list;
      std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return weight[a] > weight[b]; });
      std::vector<char> used(cols.size(), 0);
      for (size_t k : order) {
        const Overlap& o = pairs[k];
        const auto col = static_cast<size_t>(col_of[static_cast<size_t>(o.j)]);
        if (match[static_cast<size_t>(o.i)] >= 0 || used[col]) continue;
        match[static_cast<size_t>(o.i)] = o.j;
        used[col] = 1;
      }
    }
    // Drop a matching of zero weight (a row given a column it does not overlap).
    for (int i : rows) {
      int& j = match[static_cast<size_t>(i)];
      if (j < 0) continue;
      const auto it = std::lower_bound(list.begin(), list.end(), std::make_pair(i, j), [&](size_t k, const std::pair<int, int>& key) {
        return std::make_pair(pairs[k].i, pairs[k].j) < key;
      });
      if (it == list.end() || pairs[*it].i != i || pairs[*it].j != j || !(weight[*it] > 0)) j = -1;
    }
  }
  return match;
}

}  // namespace

FrameScores score_frame(const cv::Mat& ground_truth, const cv::Mat& prediction) {
  const cv::Mat gt = as_labels(ground_truth, "ground truth");
  const cv::Mat pred = as_labels(prediction, "prediction");
  if (gt.size() != pred.size())
    throw Error("prediction: size " + std::to_string(pred.cols) + "x" + std::to_string(pred.rows) +
                " differs from the ground truth " + std::to_string(gt.cols) + "x" + std::to_string(gt.rows));

  Objects g = collect_objects(gt), p = collect_objects(pred);
  FrameScores s;
  s.gt_objects = static_cast<int>(g.ids.size());
  s.pred_objects = static_cast<int>(p.ids.size());
  if (s.gt_objects == 0) return s;  // nothing to find: every score stays undefined
  const int n = s.gt_objects, m = s.pred_objects;

  // Contingency table of object pixels, its nonzero cells only: |R_i & S_j| per overlapping pair.
  const std::vector<Overlap> pairs = overlaps(gt, pred, g, p);

  // Paper: the segment with the largest overlap per ground-truth object (smallest id on ties).
  double tp_sum = 0, fp_sum = 0;
  for (size_t k = 0; k < pairs.size();) {
    size_t best = k, e = k;
    for (; e < pairs.size() && pairs[e].i == pairs[k].i; ++e)
      if (pairs[e].pixels > pairs[best].pixels) best = e;
    const Overlap& o = pairs[best];
    tp_sum += o.pixels / g.area[static_cast<size_t>(o.i)];
    fp_sum += (p.area[static_cast<size_t>(o.j)] - o.pixels) / p.area[static_cast<size_t>(o.j)];
    k = e;
  }  // a missed object (no overlap) adds 0 to both
  s.tp = tp_sum / n;
  s.fp = fp_sum / n;
  s.fn = 1.0 - s.tp;

  // UOIS: pairwise F, one-to-one matching maximising its sum; pairs without overlap do not count.
  std::vector<double> pair_f(pairs.size());
  for (size_t k = 0; k < pairs.size(); ++k)
    pair_f[k] = 2 * pairs[k].pixels / double(g.area[static_cast<size_t>(pairs[k].i)] + p.area[static_cast<size_t>(pairs[k].j)]);
  const std::vector<int> match = match_overlaps(n, m, pairs, pair_f);

  long gt_pixels = 0, pred_pixels = 0;
  for (long a : g.area) gt_pixels += a;
  for (long a : p.area) pred_pixels += a;
  double matched_pixels = 0;
  int detected = 0;
  std::vector<int> gt_of_pred(static_cast<size_t>(m), -1);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const Overlap& o = pairs[k];
    if (match[static_cast<size_t>(o.i)] != o.j) continue;
    ++s.matched;
    s.matches.emplace_back(g.ids[static_cast<size_t>(o.i)], p.ids[static_cast<size_t>(o.j)]);
    gt_of_pred[static_cast<size_t>(o.j)] = o.i;
    matched_pixels += o.pixels;
    if (pair_f[k] > 0.75) ++detected;
  }
  s.overlap_p = ratio(matched_pixels, double(pred_pixels), 0.0);
  s.overlap_r = ratio(matched_pixels, double(gt_pixels), 0.0);
  s.overlap_f = harmonic(s.overlap_p, s.overlap_r);
  s.detected_75 = double(detected) / n;

  // Boundary P/R: a predicted boundary pixel is right when a boundary pixel of its matched ground-truth
  // object lies within the tolerance disk, and vice versa for recall. Per boundary pixel, a look at
  // the disk around it: O(pixels x disk), however many objects there are.
  const cv::Mat gt_edges = object_boundaries(gt), pred_edges = object_boundaries(pred);
  const long gt_boundary = cv::countNonZero(gt_edges), pred_boundary = cv::countNonZero(pred_edges);
  const int radius = boundary_tolerance_px(gt.size());
  const cv::Mat disk = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  std::vector<cv::Point> offsets;
  for (int dy = 0; dy < disk.rows; ++dy)
    for (int dx = 0; dx < disk.cols; ++dx)
      if (disk.at<uchar>(dy, dx)) offsets.emplace_back(dx - radius, dy - radius);
  std::vector<int> pred_of_gt(static_cast<size_t>(n), -1);
  for (int i = 0; i < n; ++i) pred_of_gt[static_cast<size_t>(i)] = match[static_cast<size_t>(i)];
  // Boundary pixels of `edges_a` (labels `a`) whose matched object has a boundary pixel of `edges_b`
  // (labels `b`) within the disk.
  const auto hits = [&](const cv::Mat& a, const cv::Mat& edges_a, const Objects& oa, const std::vector<int>& partner,
                        const cv::Mat& b, const cv::Mat& edges_b, const Objects& ob) {
    double count = 0;
    for (int y = 0; y < a.rows; ++y) {
      const uchar* e = edges_a.ptr<uchar>(y);
      const int* la = a.ptr<int>(y);
      for (int x = 0; x < a.cols; ++x) {
        if (!e[x]) continue;
        const int other = partner[static_cast<size_t>(oa.index.at(la[x]))];
        if (other < 0) continue;
        const int want = ob.ids[static_cast<size_t>(other)];
        for (const cv::Point& o : offsets) {
          const int qx = x + o.x, qy = y + o.y;
          if (qx < 0 || qy < 0 || qx >= b.cols || qy >= b.rows) continue;
          if (edges_b.at<uchar>(qy, qx) && b.at<int>(qy, qx) == want) {
            ++count;
            break;
          }
        }
      }
    }
    return count;
  };
  const double pred_hits = hits(pred, pred_edges, p, gt_of_pred, gt, gt_edges, g);
  const double gt_hits = hits(gt, gt_edges, g, pred_of_gt, pred, pred_edges, p);
  // An object filling the whole image has no boundary; with nothing to miss on either side, score 1.
  const double none_to_miss = (gt_boundary == 0 && pred_boundary == 0 && s.matched > 0) ? 1.0 : 0.0;
  s.boundary_p = ratio(pred_hits, double(pred_boundary), none_to_miss);
  s.boundary_r = ratio(gt_hits, double(gt_boundary), none_to_miss);
  s.boundary_f = harmonic(s.boundary_p, s.boundary_r);
  return s;
}

MeanStd mean_std(const std::vector<double>& values) {
  MeanStd r;
  double sum = 0;
  for (double v : values)
    if (std::isfinite(v)) {
      sum += v;
      ++r.count;
    }
  if (r.count == 0) return r;
  r.mean = sum / r.count;
  double sq = 0;
  for (double v : values)
    if (std::isfinite(v)) sq += (v - r.mean) * (v - r.mean);
  r.std = std::sqrt(sq / r.count);
  return r;
}

}  // namespace clutterseg
