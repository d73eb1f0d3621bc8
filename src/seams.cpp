#include "clutterseg/seams.hpp"

#include <algorithm>
#include <cmath>

#include "clutterseg/parallel.hpp"
#include "clutterseg/patches.hpp"
#include "clutterseg/support.hpp"

namespace clutterseg {

namespace {

// Parts of a patch whose mean normals are farther apart than this meet in a crease the edges should
// have closed (a gap in the band, a box's top and front): not a seam. Splitting them would change no
// object (their junction is convex) and costs the later stages their band of edge pixels.
constexpr double kMaxAngleDeg = 30;
// Pixels per part read for its mean normal (a fixed stride over its runs).
constexpr int kNormalSamples = 1024;

// weak[i] = 1 where pixel i is in no patch or its edge value is below theta: the complement of the
// strong pixels, whose 4-connected components label_runs gives.
CLUTTERSEG_ROW_KERNEL void mark_weak(const int* __restrict label, const float* __restrict value, int n, float theta,
                                     std::uint8_t* __restrict weak) {
  for (int i = 0; i < n; ++i) weak[i] = (label[i] == 0) | (value[i] < theta);
}

// One patch with two or more large strong parts: the band between them, as edge pixels. `parts` are the
// runs of its large parts, `part` the index of each run's part (1..k). Returns the pixels marked.
int split_patch(cv::Mat& edges, const Patch& patch, const cv::Mat& patch_labels, const std::vector<LabelRun>& parts,
                const std::vector<int>& part, int count) {
  const cv::Rect box = patch.bbox;
  const int w = box.width, h = box.height;
  // The part of each pixel of the box (0: none), then the band: flood fills over the patch's pixels in
  // no part, started next to every part but the largest (a band between two parts touches one of the
  // smaller ones, so the rest of the patch is never visited).
  std::vector<int> of(static_cast<size_t>(w) * static_cast<size_t>(h), 0);
  std::vector<int> area(static_cast<size_t>(count) + 1, 0);
  for (size_t r = 0; r < parts.size(); ++r) {
    const LabelRun& run = parts[r];
    std::fill_n(of.begin() + (run.y - box.y) * w + (run.x0 - box.x), run.x1 - run.x0, part[r]);
    area[static_cast<size_t>(part[r])] += run.x1 - run.x0;
  }
  const int largest = static_cast<int>(std::max_element(area.begin(), area.end()) - area.begin());
  const int id = patch.id;
  const auto in_band = [&](int x, int y) {  // a pixel of the patch in no part, box coordinates
    return of[static_cast<size_t>(y * w + x)] == 0 && patch_labels.at<int>(box.y + y, box.x + x) == id;
  };
  std::vector<std::uint8_t> seen(of.size(), 0);
  std::vector<int> stack, region;
  int marked = 0;
  for (size_t r = 0; r < parts.size(); ++r) {
    if (part[r] == largest) continue;
    const LabelRun& run = parts[r];
    const int y = run.y - box.y;
    for (int x = run.x0 - box.x - 1; x <= run.x1 - box.x; ++x)
      for (int dy = -1; dy <= 1; ++dy) {
        const int sx = x, sy = y + dy;
        if (sx < 0 || sy < 0 || sx >= w || sy >= h || seen[static_cast<size_t>(sy * w + sx)] || !in_band(sx, sy)) continue;
        // One 8-connected region of band pixels and the parts it touches (the first and whether another).
        int first = 0;
        bool between = false;
        stack.assign(1, sy * w + sx);
        seen[static_cast<size_t>(sy * w + sx)] = 1;
        region.clear();
        while (!stack.empty()) {
          const int i = stack.back();
          stack.pop_back();
          region.push_back(i);
          const int px = i % w, py = i / w;
          for (int ny = std::max(0, py - 1); ny <= std::min(h - 1, py + 1); ++ny)
            for (int nx = std::max(0, px - 1); nx <= std::min(w - 1, px + 1); ++nx) {
              const int j = ny * w + nx;
              if (const int p = of[static_cast<size_t>(j)]; p > 0) {
                between |= first != 0 && p != first;
                first = first == 0 ? p : first;
              } else if (!seen[static_cast<size_t>(j)] && in_band(nx, ny)) {
                seen[static_cast<size_t>(j)] = 1;
                stack.push_back(j);
              }
            }
        }
        if (!between) continue;
        for (int i : region) edges.at<uchar>(box.y + i / w, box.x + i % w) = 255;
        marked += static_cast<int>(region.size());
      }
  }
  return marked;
}

}  // namespace

int split_at_seams(cv::Mat& edges, const std::vector<Patch>& patches, const cv::Mat& patch_labels,
                   const cv::Mat& edge_value, const NormalPlanes& normals, const Params::Patches& params, int min_px,
                   const cv::Mat& points, const std::optional<Plane>& table, const Params::Support& support) {
  if (params.seam_theta <= 0 || patches.empty()) return 0;
  if (patch_labels.type() != CV_32S || edge_value.type() != CV_32F || edges.type() != CV_8U ||
      patch_labels.size() != edges.size() || edge_value.size() != edges.size() || normals[0].size() != edges.size())
    throw Error("split_at_seams: patch labels (CV_32S), edge value (CV_32F), edges (CV_8U) and normals must be images of one size");
  // The strong pixels' 4-connected components (within a patch: two 4-neighbours of a patch are its
  // pixels), their sizes and patches.
  cv::Mat weak(edges.size(), CV_8U);
  const int* label = patch_labels.ptr<int>();
  mark_weak(label, edge_value.ptr<float>(), static_cast<int>(edges.total()), static_cast<float>(params.seam_theta),
            weak.ptr<std::uint8_t>());
  std::vector<LabelRun> runs;
  const int count = label_runs(weak, runs);
  std::vector<int> area(static_cast<size_t>(count), 0), patch_of(static_cast<size_t>(count), 0);
  const int cols = edges.cols;
  for (const LabelRun& run : runs) {
    area[static_cast<size_t>(run.component)] += run.x1 - run.x0;
    patch_of[static_cast<size_t>(run.component)] = label[run.y * cols + run.x0];
  }
  // The patches with two or more large parts, and their parts' runs numbered 1..k per patch.
  std::vector<int> large(patches.size() + 1, 0), number(static_cast<size_t>(count), 0);
  for (int c = 1; c < count; ++c)
    if (area[static_cast<size_t>(c)] >= min_px)
      number[static_cast<size_t>(c)] = ++large[static_cast<size_t>(patch_of[static_cast<size_t>(c)])];
  std::vector<int> candidate(patches.size() + 1, -1);
  int candidates = 0;
  for (size_t id = 1; id < large.size(); ++id)
    if (large[id] >= 2) candidate[id] = candidates++;
  if (candidates == 0) return 0;
  std::vector<std::vector<LabelRun>> parts(static_cast<size_t>(candidates));
  std::vector<std::vector<int>> part(static_cast<size_t>(candidates));
  for (const LabelRun& run : runs) {
    const auto c = static_cast<size_t>(run.component);
    const int k = candidate[static_cast<size_t>(patch_of[c])];
    if (k < 0 || number[c] == 0) continue;
    parts[static_cast<size_t>(k)].push_back(run);
    part[static_cast<size_t>(k)].push_back(number[c]);
  }
  const float* n[3] = {normals[0].ptr<float>(), normals[1].ptr<float>(), normals[2].ptr<float>()};
  const double min_cos = std::cos(params.seam_spread_deg * M_PI / 180.0), parallel_cos = std::cos(kMaxAngleDeg * M_PI / 180.0);
  int marked = 0;
  for (const Patch& patch : patches) {
    const int k = candidate[static_cast<size_t>(patch.id)];
    if (k < 0) continue;
    const std::vector<LabelRun>& its = parts[static_cast<size_t>(k)];
    const std::vector<int>& which = part[static_cast<size_t>(k)];
    const int parts_of_patch = large[static_cast<size_t>(patch.id)];
    if (!patch.table) {
      // Each part nearly planar (the length of the mean of its unit normals is the mean cosine to their
      // mean direction, as Patch::spread_deg), and all within kMaxAngleDeg of each other: a weak crease,
      // not a gap in a strong one. On at most about kNormalSamples pixels per part.
      std::vector<Eigen::Vector3d> sum(static_cast<size_t>(parts_of_patch) + 1, Eigen::Vector3d::Zero());
      std::vector<int> samples(sum.size(), 0);
      for (size_t r = 0; r < its.size(); ++r) {
        const auto p = static_cast<size_t>(which[r]);
        const int stride = std::max(1, area[static_cast<size_t>(its[r].component)] / kNormalSamples);
        for (int i = its[r].y * cols + its[r].x0, end = its[r].y * cols + its[r].x1; i < end; i += stride, ++samples[p])
          sum[p] += Eigen::Vector3d(n[0][i], n[1][i], n[2][i]);
      }
      bool seam = true;
      for (size_t a = 1; a < sum.size() && seam; ++a) {
        seam = sum[a].norm() >= min_cos * samples[a];
        for (size_t b = a + 1; b < sum.size() && seam; ++b) seam = sum[a].normalized().dot(sum[b].normalized()) >= parallel_cos;
      }
      if (!seam) continue;
    } else {
      // A table patch: only when a part but the largest would be no table (lies_in's share of points in
      // the plane's band), an object the edges did not close off; pieces of table stay one patch.
      if (!table) continue;
      std::vector<int> largest_area(static_cast<size_t>(parts_of_patch) + 1, 0);
      for (size_t r = 0; r < its.size(); ++r) largest_area[static_cast<size_t>(which[r])] += its[r].x1 - its[r].x0;
      const int largest = static_cast<int>(std::max_element(largest_area.begin(), largest_area.end()) - largest_area.begin());
      bool object = false;
      std::vector<int> pixels;
      for (int p = 1; p <= parts_of_patch && !object; ++p) {
        if (p == largest) continue;
        pixels.clear();
        for (size_t r = 0; r < its.size(); ++r)
          if (which[r] == p)
            for (int i = its[r].y * cols + its[r].x0, end = its[r].y * cols + its[r].x1; i < end; ++i) pixels.push_back(i);
        object = !mostly_within(pixels, points, *table, 0.5 * support.plane_band, 0.8);
      }
      if (!object) continue;
    }
    marked += split_patch(edges, patch, patch_labels, its, which, parts_of_patch);
  }
  return marked;
}

}  // namespace clutterseg
