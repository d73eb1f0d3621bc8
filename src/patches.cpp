#include "clutterseg/patches.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstring>
#include <numeric>
#include <opencv2/imgproc.hpp>

#include "clutterseg/normals.hpp"
#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

// Sums over the pixels of one connected component.
struct ComponentSums {
  int area = 0;
  int x0 = INT_MAX, y0 = INT_MAX, x1 = -1, y1 = -1;  // bounding box, inclusive
  double point[3] = {0, 0, 0}, normal[3] = {0, 0, 0};
  std::vector<int> pixels;
  // bins x bins counts, kCounters times over: pixel k of a run counts in copy k % kCounters, summed when
  // the patch is made. Neighbouring pixels mostly share a bin; with one counter per bin, each increment
  // would wait for the previous one.
  std::vector<int> histogram;
};
constexpr int kCounters = 4;

using Floats = float __attribute__((vector_size(16)));
using Doubles = double __attribute__((vector_size(32)));

// sum[d] += the n values of three float sequences (d = 0, 1, 2) as doubles: four at a time into the
// lanes of a 4-double vector each (lane k mod 4), three independent chains of adds instead of one
// whose latency would bound the loop, then the last n mod 4 one at a time. four(k, f) gives the
// sequences' values k .. k + 3, one(k, d) value k of sequence d. The order differs from a plain loop
// only in the last bits of the double sums, far below the float results.
template <typename Four, typename One>
inline void add_three(int n, double* __restrict sum, Four four, One one) {
  Doubles lanes[3] = {};
  int k = 0;
  for (; k + 4 <= n; k += 4) {
    Floats f[3];
    four(k, f);
    // Element by element: GCC 12 lowers __builtin_convertvector(Floats -> Doubles) to two 2-wide
    // conversions and an insert, this to one vcvtps2pd (the same exact conversion).
    for (int d = 0; d < 3; ++d) lanes[d] += Doubles{f[d][0], f[d][1], f[d][2], f[d][3]};
  }
  for (int d = 0; d < 3; ++d) sum[d] += lanes[d][0] + lanes[d][1] + lanes[d][2] + lanes[d][3];
  for (; k < n; ++k)
    for (int d = 0; d < 3; ++d) sum[d] += one(k, d);
}

// The sums of a run of n normals (planes x, y, z).
CLUTTERSEG_AVX2_KERNEL void add_normal_run(const float* __restrict nx, const float* __restrict ny,
                                           const float* __restrict nz, int n, double* __restrict sum) {
  const float* plane[3] = {nx, ny, nz};
  add_three(
      n, sum, [&](int k, Floats* f) { for (int d = 0; d < 3; ++d) std::memcpy(&f[d], plane[d] + k, sizeof f[d]); },
      [&](int k, int d) { return plane[d][k]; });
}

// The sums of a run of n points (ray_x[k] z[k], ray_y z[k], z[k]) from its depths, without reading the
// point cloud (a third of the bytes): the same float products as depth_to_points, so the same sums.
CLUTTERSEG_AVX2_KERNEL void add_point_run(const float* __restrict z, const float* __restrict ray_x, float ray_y,
                                          int n, double* __restrict sum) {
  add_three(
      n, sum,
      [&](int k, Floats* f) {
        Floats rx;
        std::memcpy(&f[2], z + k, sizeof f[2]);
        std::memcpy(&rx, ray_x + k, sizeof rx);
        f[0] = rx * f[2];
        f[1] = ray_y * f[2];
      },
      [&](int k, int d) { return d == 0 ? ray_x[k] * z[k] : d == 1 ? ray_y * z[k] : z[k]; });
}

// normal_bin of each of n normals (planes x, y), in one vectorised pass.
CLUTTERSEG_AVX2_KERNEL void normal_bins(const float* __restrict nx, const float* __restrict ny, int n, int bins,
                                        int* __restrict out) {
  for (int k = 0; k < n; ++k) out[k] = normal_bin(nx[k], ny[k], bins);
}

}  // namespace

// Two runs of adjacent rows that share a column are joined (union-find over runs, the smaller index as
// root). The runs are what the patch statistics read, so labelling them directly costs a few operations
// per run instead of a pass over every pixel.
int label_runs(const cv::Mat& edges, std::vector<LabelRun>& runs) {
  std::vector<int> parent;
  const auto root = [&](int i) { return find_root(parent, i); };
  const int cols = edges.cols;
  size_t previous_row = 0;  // index of the previous row's first run
  for (int y = 0; y < edges.rows; ++y) {
    const uchar* edge = edges.ptr<uchar>(y);
    const size_t row = runs.size();
    for (int x = first_zero(edge, 0, cols); x < cols; x = first_zero(edge, x, cols)) {
      const int start = x;
      x = first_nonzero(edge, x, cols);
      parent.push_back(static_cast<int>(runs.size()));
      runs.push_back({0, y, start, x});
    }
    // Walk both rows' runs left to right; each step drops the run that ends first.
    for (size_t a = previous_row, b = row; y > 0 && a < row && b < runs.size();) {
      if (runs[a].x0 < runs[b].x1 && runs[b].x0 < runs[a].x1) {
        const int ra = root(static_cast<int>(a)), rb = root(static_cast<int>(b));
        parent[static_cast<size_t>(std::max(ra, rb))] = std::min(ra, rb);
      }
      if (runs[a].x1 <= runs[b].x1) ++a; else ++b;
    }
    previous_row = row;
  }
  // A root is its component's first run in raster order; every other run comes after its root.
  int count = 1;
  for (size_t i = 0; i < runs.size(); ++i) {
    const int r = root(static_cast<int>(i));
    runs[i].component = r == static_cast<int>(i) ? count++ : runs[static_cast<size_t>(r)].component;
  }
  return count;
}

namespace {

// A far component need cover only a quarter of min_size pixels (from twice metric_beyond_m on).
constexpr int kFarShare = 4;

// Which components become patches: those of at least min_size pixels and, beyond `beyond_m` (beyond the
// paper; 0 = off), those covering the metric area that min_size pixels cover at `beyond_m`, judged at
// their mean depth. A face's pixel count falls with z^2 while the edge band around it keeps its width in
// pixels, so the faces of a far box would leave no patch of min_size inside them (docs/RESULTS.md
// section 20). Only the components between min_size / kFarShare and min_size read their depths.
std::vector<char> large_enough(const std::vector<LabelRun>& runs, const std::vector<ComponentSums>& sums,
                               const cv::Mat& depth, int min_size, double beyond_m) {
  std::vector<char> large(sums.size());
  for (size_t c = 0; c < sums.size(); ++c) large[c] = sums[c].area >= min_size;
  if (beyond_m <= 0) return large;
  const auto candidate = [&](int c) {
    const int area = sums[static_cast<size_t>(c)].area;
    return area < min_size && kFarShare * area >= min_size;
  };
  std::vector<double> depth_sum(sums.size(), 0.0);
  std::vector<int> with_depth(sums.size(), 0);
  for (const LabelRun& run : runs) {
    if (!candidate(run.component)) continue;
    const float* z = depth.ptr<float>(run.y);
    for (int x = run.x0; x < run.x1; ++x)
      if (valid_depth(z[x])) {
        depth_sum[static_cast<size_t>(run.component)] += z[x];
        ++with_depth[static_cast<size_t>(run.component)];
      }
  }
  for (size_t c = 1; c < sums.size(); ++c) {
    if (with_depth[c] == 0 || !candidate(static_cast<int>(c))) continue;
    const double z = depth_sum[c] / with_depth[c];
    large[c] = sums[c].area * (z / beyond_m) * (z / beyond_m) >= min_size;
  }
  return large;
}

// extract_patches, and update_patches when `previous` is given: a component with exactly the pixels of
// a previous patch takes that patch (moved), so only new components are measured.
Patches build_patches(const cv::Mat& edges, const cv::Mat& depth, const Camera& camera, const NormalPlanes& normals,
                      const Params::Patches& params, int min_size, Patches* previous) {
  const auto fits = [&](const cv::Mat& m, int type) { return m.type() == type && m.size() == edges.size(); };
  const bool planes_fit = std::all_of(normals.begin(), normals.end(), [&](const cv::Mat& n) { return fits(n, CV_32F); });
  if (!fits(edges, CV_8U) || !fits(depth, CV_32F) || !planes_fit)
    throw Error("extract_patches: edges (CV_8U), depth and the normal planes (CV_32F) must be images of one size");
  std::vector<LabelRun> runs;
  const int count = label_runs(edges, runs);
  const int bins = params.histogram_bins, cols = edges.cols;
  // First each component's area and box; then the statistics, only for the components that are large
  // enough to become patches (most components are specks along the edges).
  std::vector<ComponentSums> sums(static_cast<size_t>(count));
  for (const LabelRun& run : runs) {
    ComponentSums& s = sums[static_cast<size_t>(run.component)];
    s.area += run.x1 - run.x0;
    s.x0 = std::min(s.x0, run.x0);
    s.x1 = std::max(s.x1, run.x1 - 1);
    s.y0 = std::min(s.y0, run.y);
    s.y1 = run.y;
  }
  // The previous patch each component is (0: a new component). Edges were only added, so a component
  // lies within one previous component; with its first pixel's previous label and that patch's size, it
  // is the whole patch.
  std::vector<int> same_as(static_cast<size_t>(count), 0);
  if (previous) {
    const int* old_label = previous->labels.ptr<int>();
    int next = 1;  // components are numbered in the raster order of their first run
    for (const LabelRun& run : runs) {
      if (run.component != next) continue;  // not the component's first run
      ++next;
      const int old = old_label[run.y * cols + run.x0];
      ComponentSums& s = sums[static_cast<size_t>(run.component)];
      if (old > 0 && static_cast<size_t>(s.area) == previous->patches[static_cast<size_t>(old - 1)].pixels.size())
        same_as[static_cast<size_t>(run.component)] = old;
    }
  }
  const std::vector<char> large = large_enough(runs, sums, depth, min_size, params.metric_beyond_m);
  const auto measured = [&](int component) {
    return large[static_cast<size_t>(component)] && same_as[static_cast<size_t>(component)] == 0;
  };
  for (int c = 1; c < count; ++c)
    if (measured(c)) {
      ComponentSums& s = sums[static_cast<size_t>(c)];
      s.pixels.reserve(static_cast<size_t>(s.area));
      s.histogram.assign(static_cast<size_t>(kCounters * bins * bins), 0);
    }
  std::vector<int> bin(static_cast<size_t>(cols));  // histogram bin of each pixel of a run
  const std::vector<float> rays = ray_x(camera, cols);
  std::vector<float> row_rays(static_cast<size_t>(edges.rows));
  for (int y = 0; y < edges.rows; ++y) row_rays[static_cast<size_t>(y)] = ray_y(camera, y);
  for (const LabelRun& run : runs) {
    if (!measured(run.component)) continue;
    ComponentSums& s = sums[static_cast<size_t>(run.component)];
    const int n = run.x1 - run.x0;
    const float* nx = normals[0].ptr<float>(run.y) + run.x0;
    const float* ny = normals[1].ptr<float>(run.y) + run.x0;
    const float* nz = normals[2].ptr<float>(run.y) + run.x0;
    const size_t first = s.pixels.size();
    s.pixels.resize(first + static_cast<size_t>(n));  // within the reserved area: no reallocation
    std::iota(s.pixels.begin() + static_cast<std::ptrdiff_t>(first), s.pixels.end(), run.y * cols + run.x0);
    add_point_run(depth.ptr<float>(run.y) + run.x0, rays.data() + run.x0, row_rays[static_cast<size_t>(run.y)], n,
                  s.point);
    add_normal_run(nx, ny, nz, n, s.normal);
    normal_bins(nx, ny, n, bins, bin.data());
    int* const counts = s.histogram.data();
    const int cells = bins * bins;
    int k = 0;
    for (; k + kCounters <= n; k += kCounters)
#pragma GCC unroll 4
      for (int copy = 0; copy < kCounters; ++copy) ++counts[copy * cells + bin[static_cast<size_t>(k + copy)]];
    for (; k < n; ++k) ++counts[(k % kCounters) * cells + bin[static_cast<size_t>(k)]];
  }

  // Components large enough become patches 1..N, in raster order.
  std::vector<int> new_id(static_cast<size_t>(count), 0);
  Patches out;
  for (int c = 1; c < count; ++c) {
    ComponentSums& s = sums[static_cast<size_t>(c)];
    if (!large[static_cast<size_t>(c)]) continue;
    new_id[static_cast<size_t>(c)] = static_cast<int>(out.patches.size()) + 1;
    if (const int old = same_as[static_cast<size_t>(c)]; old > 0) {
      out.patches.push_back(std::move(previous->patches[static_cast<size_t>(old - 1)]));
      out.patches.back().id = new_id[static_cast<size_t>(c)];
      continue;
    }
    Patch p;
    p.id = new_id[static_cast<size_t>(c)];
    p.bbox = cv::Rect(s.x0, s.y0, s.x1 - s.x0 + 1, s.y1 - s.y0 + 1);
    const double n = s.area;
    const Eigen::Vector3d normal_sum(s.normal[0], s.normal[1], s.normal[2]);
    p.centroid = Eigen::Vector3f(static_cast<float>(s.point[0] / n), static_cast<float>(s.point[1] / n),
                                 static_cast<float>(s.point[2] / n));
    p.mean_normal = normal_sum.norm() > 0 ? Eigen::Vector3f(normal_sum.normalized().cast<float>()) : Eigen::Vector3f(0, 0, -1);
    // Mean angular deviation, taken as the angle of the mean normal's length: |mean of unit normals|
    // = mean cos(deviation) for small spreads; one acos per patch instead of one per pixel.
    p.spread_deg = static_cast<float>(std::acos(std::clamp(normal_sum.norm() / n, 0.0, 1.0)) * 180.0 / M_PI);
    const size_t cells = static_cast<size_t>(bins * bins);
    p.histogram.resize(cells);
    for (size_t b = 0; b < cells; ++b) {
      int count = 0;
      for (size_t copy = 0; copy < kCounters; ++copy) count += s.histogram[copy * cells + b];
      p.histogram[b] = static_cast<float>(count) * static_cast<float>(1.0 / n);
    }
    p.occupied_bins = static_cast<int>(std::count_if(p.histogram.begin(), p.histogram.end(),
        [&](float h) { return h >= params.occupied_share; }));
    p.curved = p.occupied_bins >= params.flat_max_bins;
    p.pixels = std::move(s.pixels);
    out.patches.push_back(std::move(p));
  }
  // The patch image, run by run (edge pixels and small components 0).
  out.labels = cv::Mat(edges.size(), CV_32S);
  int* const labels = out.labels.ptr<int>();
  size_t done = 0;  // pixels written, in raster order
  for (const LabelRun& run : runs) {
    const size_t begin = static_cast<size_t>(run.y) * static_cast<size_t>(cols), from = begin + static_cast<size_t>(run.x0);
    std::fill(labels + done, labels + from, 0);
    done = begin + static_cast<size_t>(run.x1);
    std::fill(labels + from, labels + done, new_id[static_cast<size_t>(run.component)]);
  }
  std::fill(labels + done, labels + edges.total(), 0);
  return out;
}

}  // namespace

Patches extract_patches(const cv::Mat& edges, const cv::Mat& depth, const Camera& camera,
                        const NormalPlanes& normals, const Params::Patches& params, int min_size) {
  return build_patches(edges, depth, camera, normals, params, min_size, nullptr);
}

Patches update_patches(Patches previous, const cv::Mat& edges, const cv::Mat& depth, const Camera& camera,
                       const NormalPlanes& normals, const Params::Patches& params, int min_size) {
  if (previous.labels.size() != edges.size() || previous.labels.type() != CV_32S)
    throw Error("update_patches: the previous patch image must be CV_32S of the edges' size");
  return build_patches(edges, depth, camera, normals, params, min_size, &previous);
}

void separate_marked(cv::Mat& edges, const cv::Mat& mark_image, const cv::Mat& patch_labels) {
  if (mark_image.size() != patch_labels.size() || mark_image.type() != CV_8U || edges.size() != patch_labels.size())
    throw Error("separate_marked: mark and edges must be CV_8U images of the patch image's size");
  const uchar* mark = mark_image.ptr<uchar>();
  const int* lab = patch_labels.ptr<int>();
  uchar* edge = edges.ptr<uchar>();
  const int width = patch_labels.cols, height = patch_labels.rows;
  for (int y = 0; y < height; ++y)
    // Marked pixels are few: the rest of a row is skipped eight at a time.
    for (int x = first_nonzero(mark + y * width, 0, width); x < width; x = first_nonzero(mark + y * width, x + 1, width)) {
      const int i = y * width + x;
      const int neighbours[4] = {x > 0 ? i - 1 : -1, x + 1 < width ? i + 1 : -1, y > 0 ? i - width : -1,
                                 y + 1 < height ? i + width : -1};
      for (int j : neighbours)
        if (j >= 0 && !mark[j] && lab[j] == lab[i]) edge[i] = edge[j] = 255;
    }
}

}  // namespace clutterseg
