// Paper d): adjacency and edge-pixel assignment.
//
// Speed (see docs/ADJACENCY.md): the naive scan reads every pixel of a disc of radius r around every
// edge pixel, O(edge pixels x r^2) - 40-90 ms at 640x480 (r = 14). Here the patches are propagated
// into the edge region instead, one ring of pixels at a time (a bounded multi-source BFS): every
// non-patch pixel keeps, per patch that reached it, the one seed point (a patch pixel) nearest to it in
// 3D, chosen among the seeds its 8 neighbours of the previous ring kept (and the patch pixels touching
// it). Seeds travel at most r pixels (Euclidean, image) from where they started; pixels without depth
// pass on the seeds nearest in the image. Each edge pixel then does what the paper says with its
// seeds: all patches with a seed closer than d_max become pairwise adjacent, and the pixel joins the
// patch of the nearest seed. Cost: O(edge pixels x 8 x seeds kept), seeds kept <= kMaxSeeds.
// What changes against the naive scan: a patch is seen only through a chain of non-patch pixels (not
// across another patch), and the nearest point is the nearest among the propagated seeds, not among
// all patch pixels of the disc. tests/test_adjacency.cpp compares with the naive scan.
#include "clutterseg/adjacency.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

namespace clutterseg {

namespace {

bool valid_point(const cv::Vec3f& p) { return p[2] > 0 && std::isfinite(p[2]); }

float squared_distance(const cv::Vec3f& a, const cv::Vec3f& b) {
  const cv::Vec3f d = a - b;
  return d.dot(d);
}

// Seeds kept per pixel: one per patch, the nearest kMaxSeeds patches.
constexpr int kMaxSeeds = 4;

struct Seed {
  cv::Vec3f point;    // the patch pixel's 3D point (carried along: no random reads of the cloud)
  int label;          // patch id 1..N
  int pixel;          // linear index of the patch pixel
  std::int16_t x, y;  // its image position (no division in the inner loop)
  float d2;    // squared 3D distance to the pixel holding it; for a pixel without depth, the squared
               // image distance instead (it only relays, keeping the seeds nearest in the image)
};

struct SeedSet {
  Seed seed[kMaxSeeds];
  int count = 0;
  // Keeps the nearest seed per label and the kMaxSeeds nearest labels; ties go to the smaller pixel
  // index so that the result does not depend on the order neighbours are visited.
  void offer(const Seed& s) {
    for (int i = 0; i < count; ++i)
      if (seed[i].label == s.label) {
        if (s.d2 < seed[i].d2 || (s.d2 == seed[i].d2 && s.pixel < seed[i].pixel)) seed[i] = s;
        return;
      }
    if (count < kMaxSeeds) { seed[count++] = s; return; }
    int worst = 0;
    for (int i = 1; i < count; ++i)
      if (seed[i].d2 > seed[worst].d2 || (seed[i].d2 == seed[worst].d2 && seed[i].label > seed[worst].label)) worst = i;
    if (s.d2 < seed[worst].d2 || (s.d2 == seed[worst].d2 && s.label < seed[worst].label)) seed[worst] = s;
  }
};

constexpr int kDx[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
constexpr int kDy[8] = {-1, -1, -1, 0, 0, 1, 1, 1};

}  // namespace

Assignment assign_edge_pixels(const cv::Mat& patch_labels, const cv::Mat& points, int num_patches,
                              int radius_px, double d_max) {
  if (patch_labels.type() != CV_32S || points.type() != CV_32FC3 || patch_labels.size() != points.size())
    throw Error("assign_edge_pixels: labels must be CV_32S and points CV_32FC3 of the same size");
  const int width = patch_labels.cols, height = patch_labels.rows;
  const int total = width * height;
  const int r = std::max(0, radius_px);
  const float d2_max = static_cast<float>(d_max * d_max);
  Assignment out;
  out.labels = patch_labels.clone();
  if (num_patches <= 0 || total == 0 || r == 0) return out;
  const int* lab = patch_labels.ptr<int>();
  const auto* pts = points.ptr<cv::Vec3f>();

  // Pixels that carry seeds: non-patch pixels with depth, and pixels without depth next to one (seeds
  // cross holes of 1-2 px inside an edge band, but do not flood the large regions without depth).
  auto next_to_depth = [&](int x, int y) {
    for (int n = 0; n < 8; ++n) {
      const int xx = x + kDx[n], yy = y + kDy[n];
      if (xx >= 0 && yy >= 0 && xx < width && yy < height && valid_point(pts[yy * width + xx])) return true;
    }
    return false;
  };
  std::vector<std::uint8_t> patch_pixel(static_cast<size_t>(total), 0);  // a patch pixel with depth
  for (int i = 0; i < total; ++i) patch_pixel[static_cast<size_t>(i)] = lab[i] > 0 && lab[i] <= num_patches && valid_point(pts[i]);
  std::vector<int> slot(static_cast<size_t>(total), -1);  // index into seeds, -1 = patch or no carrier
  std::vector<int> carriers;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const int i = y * width + x;
      if (lab[i] != 0 || !(valid_point(pts[i]) || next_to_depth(x, y))) continue;
      slot[static_cast<size_t>(i)] = static_cast<int>(carriers.size());
      carriers.push_back(i);
    }
  std::vector<SeedSet> seeds(carriers.size());

  // Two raster passes (forward: from W, NW, N, NE; backward: from E, SE, S, SW), as in a chamfer
  // distance transform: a seed reaches every pixel within r along a path the passes follow.
  const int r2 = r * r;
  auto gather = [&](int i, const int (&from)[4][2]) {
    const int x = i % width, y = i / width;
    const bool has_point = valid_point(pts[i]);
    SeedSet& own = seeds[static_cast<size_t>(slot[static_cast<size_t>(i)])];
    const cv::Vec3f here = pts[i];
    auto offer = [&](const cv::Vec3f& point, int label, int pixel, int sx, int sy) {
      const int dx = sx - x, dy = sy - y;
      if (dx * dx + dy * dy > r2) return;
      for (int s = 0; s < own.count; ++s)  // neighbours mostly pass on the same seed
        if (own.seed[s].pixel == pixel) return;
      own.offer({point, label, pixel, static_cast<std::int16_t>(sx), static_cast<std::int16_t>(sy),
                 has_point ? squared_distance(here, point) : static_cast<float>(dx * dx + dy * dy)});
    };
    for (const auto& d : from) {
      const int xx = x + d[0], yy = y + d[1];
      if (xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
      const int j = yy * width + xx;
      if (patch_pixel[static_cast<size_t>(j)]) {
        offer(pts[j], lab[j], j, xx, yy);
      } else if (slot[static_cast<size_t>(j)] >= 0) {
        const SeedSet& other = seeds[static_cast<size_t>(slot[static_cast<size_t>(j)])];
        for (int s = 0; s < other.count; ++s) {
          const Seed& t = other.seed[s];
          offer(t.point, t.label, t.pixel, t.x, t.y);
        }
      }
    }
  };
  constexpr int kForward[4][2] = {{-1, 0}, {-1, -1}, {0, -1}, {1, -1}};
  constexpr int kBackward[4][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}};
  for (int i : carriers) gather(i, kForward);
  for (auto it = carriers.rbegin(); it != carriers.rend(); ++it) gather(*it, kBackward);
  const std::vector<int>& reached = carriers;

  // The paper's rule on each reached pixel with depth: seeds within d_max.
  int* assigned = out.labels.ptr<int>();
  for (int i : reached) {
    if (!valid_point(pts[i])) continue;
    const SeedSet& own = seeds[static_cast<size_t>(slot[static_cast<size_t>(i)])];
    int near[kMaxSeeds], count = 0, best = -1;
    for (int s = 0; s < own.count; ++s) {
      if (own.seed[s].d2 >= d2_max) continue;
      near[count++] = own.seed[s].label;
      if (best < 0 || own.seed[s].d2 < own.seed[best].d2 ||
          (own.seed[s].d2 == own.seed[best].d2 && own.seed[s].label < own.seed[best].label)) best = s;
    }
    if (best < 0) continue;
    assigned[i] = own.seed[best].label;
    for (int a = 0; a < count; ++a)
      for (int b = a + 1; b < count; ++b)
        out.adjacent.emplace_back(std::min(near[a], near[b]) - 1, std::max(near[a], near[b]) - 1);
  }
  std::sort(out.adjacent.begin(), out.adjacent.end());
  out.adjacent.erase(std::unique(out.adjacent.begin(), out.adjacent.end()), out.adjacent.end());
  return out;
}

}  // namespace clutterseg
