// Finding the patches of a segmented test scene by its ground-truth labels.
#pragma once

#include <algorithm>
#include <map>
#include <vector>

#include "clutterseg/segmenter.hpp"
#include "scenes.hpp"

namespace clutterseg::scenes {

struct Segmented {
  synth::Rendering truth;
  Result result;
};

inline Segmented segment_scene(const TestScene& scene, const Params& params = {}) {
  Segmented s{scene.render(), {}};
  s.result = segment(s.truth.depth, scene.camera, params);
  return s;
}

// Majority ground-truth label of a pixel list (0 = table).
inline int majority_label(const std::vector<int>& pixels, const cv::Mat& truth_labels) {
  std::map<int, int> count;
  for (int i : pixels) ++count[truth_labels.ptr<int>()[i]];
  if (count.empty()) return 0;
  return std::max_element(count.begin(), count.end(), [](auto& a, auto& b) { return a.second < b.second; })->first;
}

// Share of the measured pixels of ground-truth `label` that `view` labels non-zero.
inline double kept_share(const cv::Mat& view, const cv::Mat& truth, int label, const cv::Mat& depth) {
  int n = 0, kept = 0;
  for (int i = 0; i < static_cast<int>(view.total()); ++i) {
    if (truth.ptr<int>()[i] != label || depth.ptr<float>()[i] <= 0) continue;
    ++n;
    kept += view.ptr<int>()[i] > 0;
  }
  return n ? static_cast<double>(kept) / n : 0.0;
}

// Indices of the patches lying entirely on ground-truth object `label`, in patch order.
inline std::vector<int> patches_on(const Segmented& s, int label) {
  std::vector<int> out;
  const int* truth = s.truth.labels.ptr<int>();
  for (size_t i = 0; i < s.result.patches.size(); ++i) {
    const auto& pixels = s.result.patches[i].pixels;
    bool pure = !pixels.empty();
    for (int k : pixels) pure = pure && truth[k] == label;
    if (pure) out.push_back(static_cast<int>(i));
  }
  return out;
}

// Among `candidates`, those whose mean normal is within ~25 degrees of `direction` (camera frame).
inline std::vector<int> facing(const Segmented& s, const std::vector<int>& candidates, const Eigen::Vector3f& direction) {
  std::vector<int> out;
  for (int i : candidates)
    if (s.result.patches[static_cast<size_t>(i)].mean_normal.dot(direction.normalized()) > 0.9f) out.push_back(i);
  return out;
}

// Camera-frame direction of a world-frame direction.
inline Eigen::Vector3f camera_direction(const TestScene& scene, const Eigen::Vector3d& world) {
  return (scene.world_to_camera.linear() * world).cast<float>();
}

inline Eigen::Vector3f direction_up(const TestScene& scene) { return camera_direction(scene, Eigen::Vector3d::UnitZ()); }

}  // namespace clutterseg::scenes
