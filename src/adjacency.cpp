// Paper d): adjacency and edge-pixel assignment.
//
// Speed-up over the naive window scan (see docs/ADJACENCY.md): an edge pixel only looks at the
// *boundary* pixels of the patches in its disc (patch pixels with an 8-neighbour of another label),
// found through a per-row index instead of reading every pixel of the window. Any patch pixel q inside
// the disc around p is reached from p by a digital line that stays inside the disc and enters q's patch
// at a boundary pixel, so "which patches lie within r in the image" is unchanged. What can change is
// the 3D test: a patch whose boundary pixels in the disc are all >= d_max away while one of its interior
// pixels is closer is missed, and the nearest point is the nearest boundary point. Both need a surface
// that folds back towards the edge pixel inside a few millimetres; on the test scenes the result equals
// the naive scan (tests/test_adjacency.cpp keeps the naive scan as the reference).
#include "clutterseg/adjacency.hpp"

#include <algorithm>
#include <cmath>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

struct BoundaryPixel {
  int x;
  int label;
  cv::Vec3f point;
};

bool valid_point(const cv::Vec3f& p) { return p[2] > 0 && std::isfinite(p[2]); }

float squared_distance(const cv::Vec3f& a, const cv::Vec3f& b) {
  const cv::Vec3f d = a - b;
  return d.dot(d);
}

// Patches seen by one edge pixel: few in practice, so a small linear list.
struct Seen {
  static constexpr int kMax = 16;
  int label[kMax];
  int count = 0;
  void add(int l) {
    for (int i = 0; i < count; ++i)
      if (label[i] == l) return;
    if (count < kMax) label[count++] = l;
  }
};

}  // namespace

Assignment assign_edge_pixels(const cv::Mat& patch_labels, const cv::Mat& points, int num_patches,
                              int radius_px, double d_max) {
  if (patch_labels.type() != CV_32S || points.type() != CV_32FC3 || patch_labels.size() != points.size())
    throw Error("assign_edge_pixels: labels must be CV_32S and points CV_32FC3 of the same size");
  const int width = patch_labels.cols, height = patch_labels.rows;
  const int r = std::max(0, radius_px);
  const float d2_max = static_cast<float>(d_max * d_max);
  Assignment out;
  out.labels = patch_labels.clone();
  if (num_patches <= 0 || width == 0 || height == 0) return out;

  // Boundary pixels per row, sorted by x, and first_at[y][x] = index of the first one at or after x.
  std::vector<std::vector<BoundaryPixel>> boundary(static_cast<size_t>(height));
  cv::Mat first_at(height, width + 1, CV_32S);
  parallel_for_rows(height, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const int* lab = patch_labels.ptr<int>(y);
      const auto* pts = points.ptr<cv::Vec3f>(y);
      int* first = first_at.ptr<int>(y);
      auto& row = boundary[static_cast<size_t>(y)];
      for (int x = 0; x < width; ++x) {
        first[x] = static_cast<int>(row.size());
        const int l = lab[x];
        if (l <= 0 || l > num_patches || !valid_point(pts[x])) continue;
        bool on_boundary = false;
        for (int dy = -1; dy <= 1 && !on_boundary; ++dy) {
          const int yy = y + dy;
          if (yy < 0 || yy >= height) continue;
          const int* nl = patch_labels.ptr<int>(yy);
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx;
            if (xx >= 0 && xx < width && nl[xx] != l) { on_boundary = true; break; }
          }
        }
        if (on_boundary) row.push_back({x, l, pts[x]});
      }
      first[width] = static_cast<int>(row.size());
    }
  });

  std::vector<int> half_width(static_cast<size_t>(r) + 1);
  for (int dy = 0; dy <= r; ++dy) half_width[static_cast<size_t>(dy)] = static_cast<int>(std::floor(std::sqrt(double(r * r - dy * dy))));

  std::vector<std::vector<PatchPair>> row_pairs(static_cast<size_t>(height));
  parallel_for_rows(height, [&](int begin, int end) {
    for (int y = begin; y < end; ++y) {
      const int* lab = patch_labels.ptr<int>(y);
      const auto* pts = points.ptr<cv::Vec3f>(y);
      int* assigned = out.labels.ptr<int>(y);
      auto& pairs = row_pairs[static_cast<size_t>(y)];
      for (int x = 0; x < width; ++x) {
        if (lab[x] != 0 || !valid_point(pts[x])) continue;
        const cv::Vec3f p = pts[x];
        Seen seen;
        float best = d2_max;
        int best_label = 0;
        for (int yy = std::max(0, y - r); yy <= std::min(height - 1, y + r); ++yy) {
          const int w = half_width[static_cast<size_t>(std::abs(yy - y))];
          const int* first = first_at.ptr<int>(yy);
          const int k0 = first[std::max(0, x - w)], k1 = first[std::min(width, x + w + 1)];
          const BoundaryPixel* row = boundary[static_cast<size_t>(yy)].data();
          for (int k = k0; k < k1; ++k) {
            const float d2 = squared_distance(p, row[k].point);
            if (d2 >= d2_max) continue;
            seen.add(row[k].label);
            // Ties go to the smaller label so the result does not depend on scan order.
            if (d2 < best || (d2 == best && row[k].label < best_label)) { best = d2; best_label = row[k].label; }
          }
        }
        if (best_label == 0) continue;
        assigned[x] = best_label;
        for (int i = 0; i < seen.count; ++i)
          for (int j = i + 1; j < seen.count; ++j) {
            const int a = std::min(seen.label[i], seen.label[j]) - 1, b = std::max(seen.label[i], seen.label[j]) - 1;
            pairs.emplace_back(a, b);
          }
        // Neighbouring edge pixels mostly see the same pairs: keep the row list short.
        if (pairs.size() > 256) {
          std::sort(pairs.begin(), pairs.end());
          pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
        }
      }
    }
  });
  for (auto& pairs : row_pairs) out.adjacent.insert(out.adjacent.end(), pairs.begin(), pairs.end());
  std::sort(out.adjacent.begin(), out.adjacent.end());
  out.adjacent.erase(std::unique(out.adjacent.begin(), out.adjacent.end()), out.adjacent.end());
  return out;
}

}  // namespace clutterseg
