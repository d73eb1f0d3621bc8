#include "clutterseg/tracking_metrics.hpp"

#include <limits>
#include <vector>

namespace clutterseg {

namespace {

cv::Mat as_int_labels(const cv::Mat& image, const char* what) {
  if (image.empty() || image.channels() != 1) throw Error(std::string(what) + ": not a single-channel label image");
  if (image.depth() == CV_32S) return image;
  if (image.depth() != CV_16U && image.depth() != CV_8U) throw Error(std::string(what) + ": label image must hold integer ids");
  cv::Mat out;
  image.convertTo(out, CV_32S);
  return out;
}

}  // namespace

TrackingScores& TrackingScores::operator+=(const TrackingScores& o) {
  object_frames += o.object_frames;
  matched += o.matched;
  steps += o.steps;
  kept += o.kept;
  switches += o.switches;
  false_positives += o.false_positives;
  objects += o.objects;
  reused_ids += o.reused_ids;
  frames += o.frames;
  return *this;
}

void TrackingScorer::add(const cv::Mat& ground_truth, const cv::Mat& prediction) {
  const cv::Mat gt = as_int_labels(ground_truth, "ground truth"), pred = as_int_labels(prediction, "prediction");
  if (gt.size() != pred.size()) throw Error("tracking scores: ground truth and prediction differ in size");
  // Pixel counts per (gt, pred) pair, run by run.
  std::map<std::pair<int, int>, long> pairs;
  for (int y = 0; y < gt.rows; ++y) {
    const int* g = gt.ptr<int>(y);
    const int* p = pred.ptr<int>(y);
    for (int x = 0; x < gt.cols;) {
      int end = x + 1;
      while (end < gt.cols && g[end] == g[x] && p[end] == p[x]) ++end;
      pairs[{g[x], p[x]}] += end - x;
      x = end;
    }
  }
  std::map<int, long> gt_area, pred_area;
  for (const auto& [key, n] : pairs) {
    gt_area[key.first] += n;
    pred_area[key.second] += n;
  }
  gt_area.erase(0);
  pred_area.erase(0);
  ++scores_.frames;
  std::set<int> matched_pred;
  for (const auto& [g, area] : gt_area) {
    ++scores_.object_frames;
    if (seen_.insert(g).second) ++scores_.objects;
    int match = 0;
    // Only the predictions that overlap g (the pairs are sorted by g): bounded by the pixels, not the ids.
    for (auto it = pairs.lower_bound({g, std::numeric_limits<int>::min()}); it != pairs.end() && it->first.first == g; ++it) {
      const int p = it->first.second;
      if (p == 0) continue;
      const long p_area = pred_area.at(p);
      const double iou = static_cast<double>(it->second) / static_cast<double>(area + p_area - it->second);
      if (iou > 0.5) match = p;  // at most one: IoU > 0.5 is one-to-one
    }
    if (match == 0) continue;
    ++scores_.matched;
    matched_pred.insert(match);
    std::set<int>& owners = objects_of_[match];
    if (owners.insert(g).second && owners.size() == 2) ++scores_.reused_ids;
    const auto last = last_id_.find(g);
    if (last != last_id_.end()) {
      ++scores_.steps;
      if (last->second == match) ++scores_.kept;
      else ++scores_.switches;
    }
    last_id_[g] = match;
  }
  scores_.false_positives += static_cast<long>(pred_area.size() - matched_pred.size());
}

}  // namespace clutterseg
