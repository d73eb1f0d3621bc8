#include "clutterseg/metrics.hpp"

#include <algorithm>
#include <cmath>
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

// Pixels of `boundaries` that belong to object `id`, inside `roi`.
cv::Mat object_boundary(const cv::Mat& labels, const cv::Mat& boundaries, int id, const cv::Rect& roi) {
  return (labels(roi) == id) & boundaries(roi);
}

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

  // Contingency table of object pixels: intersection[i][j] = |R_i & S_j|.
  std::vector<std::vector<double>> intersection(n, std::vector<double>(m, 0.0));
  if (m > 0) {
    for (int y = 0; y < gt.rows; ++y) {
      const int* gr = gt.ptr<int>(y);
      const int* pr = pred.ptr<int>(y);
      for (int x = 0; x < gt.cols; ++x)
        if (gr[x] != 0 && pr[x] != 0) intersection[g.index[gr[x]]][p.index[pr[x]]] += 1;
    }
  }

  // Paper: the segment with the largest overlap per ground-truth object.
  double tp_sum = 0, fp_sum = 0;
  for (int i = 0; i < n; ++i) {
    int best = -1;
    for (int j = 0; j < m; ++j)
      if (intersection[i][j] > 0 && (best < 0 || intersection[i][j] > intersection[i][best])) best = j;
    if (best < 0) continue;  // missed: tp_i = 0, and no segment to be wrong (fp_i = 0)
    tp_sum += intersection[i][best] / g.area[i];
    fp_sum += (p.area[best] - intersection[i][best]) / p.area[best];
  }
  s.tp = tp_sum / n;
  s.fp = fp_sum / n;
  s.fn = 1.0 - s.tp;

  // UOIS: pairwise F, one-to-one matching maximising its sum; pairs without overlap do not count.
  std::vector<std::vector<double>> pair_f(n, std::vector<double>(m, 0.0));
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) pair_f[i][j] = 2 * intersection[i][j] / double(g.area[i] + p.area[j]);
  const std::vector<int> match = m > 0 ? max_weight_assignment(pair_f) : std::vector<int>(n, -1);

  long gt_pixels = 0, pred_pixels = 0;
  for (long a : g.area) gt_pixels += a;
  for (long a : p.area) pred_pixels += a;
  double matched_pixels = 0;
  int detected = 0;
  for (int i = 0; i < n; ++i) {
    if (match[i] < 0 || pair_f[i][match[i]] <= 0) continue;
    ++s.matched;
    s.matches.emplace_back(g.ids[i], p.ids[match[i]]);
    matched_pixels += intersection[i][match[i]];
    if (pair_f[i][match[i]] > 0.75) ++detected;
  }
  s.overlap_p = ratio(matched_pixels, double(pred_pixels), 0.0);
  s.overlap_r = ratio(matched_pixels, double(gt_pixels), 0.0);
  s.overlap_f = harmonic(s.overlap_p, s.overlap_r);
  s.detected_75 = double(detected) / n;

  // Boundary P/R: a predicted boundary pixel is right when a matched ground-truth boundary lies within
  // the tolerance disk, and vice versa for recall.
  const cv::Mat gt_edges = object_boundaries(gt), pred_edges = object_boundaries(pred);
  const long gt_boundary = cv::countNonZero(gt_edges), pred_boundary = cv::countNonZero(pred_edges);
  const int radius = boundary_tolerance_px(gt.size());
  const cv::Mat disk = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  const cv::Rect image(0, 0, gt.cols, gt.rows);
  double pred_hits = 0, gt_hits = 0;
  for (int i = 0; i < n; ++i) {
    if (match[i] < 0 || pair_f[i][match[i]] <= 0) continue;
    const int j = match[i];
    cv::Rect roi = g.bbox[i] | p.bbox[j];
    roi = cv::Rect(roi.x - radius, roi.y - radius, roi.width + 2 * radius, roi.height + 2 * radius) & image;
    const cv::Mat gb = object_boundary(gt, gt_edges, g.ids[i], roi);
    const cv::Mat pb = object_boundary(pred, pred_edges, p.ids[j], roi);
    cv::Mat gb_wide, pb_wide;
    cv::dilate(gb, gb_wide, disk, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::dilate(pb, pb_wide, disk, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
    pred_hits += cv::countNonZero(pb & gb_wide);
    gt_hits += cv::countNonZero(gb & pb_wide);
  }
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
