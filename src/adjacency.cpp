// Paper d): adjacency and edge-pixel assignment.
//
// Speed (see docs/ADJACENCY.md): the naive scan reads every pixel of a disc of radius r around every
// edge pixel, O(edge pixels x r^2) - 40-90 ms at 640x480 (r = 14). Here the patches are propagated
// into the edge region instead, in two raster passes as in a chamfer distance transform: every
// non-patch pixel keeps, per patch that reached it, the one seed (a patch pixel) nearest to it in 3D,
// chosen among the seeds of its already visited neighbours (and the patch pixels touching it). Seeds
// travel at most r pixels (Euclidean, image) from where they started; a pixel with depth keeps only
// seeds closer than d_max (the only ones the rule uses), pixels without depth pass on the seeds
// nearest in the image. Each edge pixel then does what the paper says with its seeds: all patches with
// a seed become pairwise adjacent, and the pixel joins the patch of the nearest seed.
// Cost: O(edge pixels x 6 x seeds kept), seeds kept <= kMaxSeeds.
// What changes against the naive scan: a patch is seen only through a chain of non-patch pixels (not
// across another patch) that keep its seed, and the nearest point is the nearest among the propagated
// seeds, not among all patch pixels of the disc. tests/test_adjacency.cpp compares with the naive scan.
#include "clutterseg/adjacency.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <type_traits>

#include "clutterseg/limits.hpp"
#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

// Seeds kept per pixel: one per patch, the nearest kMaxSeeds patches. Two: an edge pixel lies where two
// surfaces meet. At a corner a third patch within d_max is heard by the pixels along its own borders with
// each of the two. Four seeds gave the same scores on every set and 6 more of 2881 graph links
// (docs/ADJACENCY.md, "Two seeds") in sets twice as large, and the sets' size is what the passes pay for.
constexpr int kMaxSeeds = 2;

// A seed is a patch pixel, named by its image position and carrying its label; its 3D point is read
// from the cloud when a distance is needed (it lies within r pixels, so in cache).
struct Seed {
  std::uint32_t yx;  // (y << 16) | x: one compare tells two seeds apart, and orders them as pixel indices
  int label;         // patch id 1..N
  float d2;          // squared 3D distance to the pixel holding it; for a pixel without depth, the squared
                     // image distance instead (it only relays, keeping the seeds nearest in the image)
};

std::uint32_t pack(int x, int y) { return static_cast<std::uint32_t>(y) << 16 | static_cast<std::uint32_t>(x); }

// The yx of an empty slot: no pixel of a frame has it (frames are at most kMaxFrameSide wide).
constexpr std::uint32_t kNoSeed = 0xffffffffu;
static_assert(kMaxFrameSide <= 0xffff, "pack() keeps x and y in 16 bits each, below kNoSeed");

// The seeds a pixel holds, stored as arrays (28 bytes; the sets of all carriers of a 640x480 frame take
// about 1.5 MB). Most of the work is asking whether a seed is held already: one compare per slot without
// a branch (empty slots hold kNoSeed), instead of a loop whose exit a CPU cannot predict.
struct SeedSet {
  std::uint32_t yx[kMaxSeeds];
  int label[kMaxSeeds];
  float d2[kMaxSeeds];
  int count;
  void clear() {
    std::fill(yx, yx + kMaxSeeds, kNoSeed);
    count = 0;
  }
  bool holds(std::uint32_t pixel) const {
    static_assert(kMaxSeeds == 2, "holds() compares two slots");
    return (yx[0] == pixel) | (yx[1] == pixel);
  }
  Seed at(int i) const { return {yx[i], label[i], d2[i]}; }
  void put(int i, const Seed& s) { yx[i] = s.yx; label[i] = s.label; d2[i] = s.d2; }
  // Offers a seed not held yet: keeps the nearest seed per label and the kMaxSeeds nearest labels.
  // `within` tells whether the candidate is within the search radius, `distance2` gives its d2; seeds
  // at `limit` or farther are not kept. Ties go to the smaller pixel index or label, so that the result
  // does not depend on the order neighbours are visited.
  template <typename Within, typename Distance2>
  void offer(std::uint32_t pixel, int seed_label, Within within, Distance2 distance2, float limit) {
    if (!within()) return;
    int slot = -1;
    for (int i = 0; i < count; ++i)
      if (label[i] == seed_label) {
        slot = i;
        break;
      }
    const Seed s{pixel, seed_label, distance2()};
    if (s.d2 >= limit) return;
    if (slot >= 0) {
      if (s.d2 < d2[slot] || (s.d2 == d2[slot] && s.yx < yx[slot])) put(slot, s);
      return;
    }
    if (count < kMaxSeeds) { put(count++, s); return; }
    int worst = 0;
    for (int i = 1; i < count; ++i)
      if (d2[i] > d2[worst] || (d2[i] == d2[worst] && label[i] > label[worst])) worst = i;
    if (s.d2 < d2[worst] || (s.d2 == d2[worst] && s.label < label[worst])) put(worst, s);
  }
};

// 255 where the point (interleaved xyz) has depth, else 0.
CLUTTERSEG_ROW_KERNEL void mark_depth(const float* __restrict xyz, int count, uchar* __restrict out) {
  for (int i = 0; i < count; ++i) out[i] = valid_depth(xyz[3 * i + 2]) ? 255 : 0;
}

// near[x] = 255 where a pixel of the 3x3 block around x has depth: rows up, mid, down of the depth mask,
// padded by one 0 at both ends (index x + 1 is pixel x).
CLUTTERSEG_ROW_KERNEL void mark_near_depth(const uchar* __restrict up, const uchar* __restrict mid,
                                          const uchar* __restrict down, int cols, uchar* __restrict near) {
  for (int x = 0; x < cols; ++x)
    near[x] = up[x] | up[x + 1] | up[x + 2] | mid[x] | mid[x + 1] | mid[x + 2] | down[x] | down[x + 1] | down[x + 2];
}

// role = source where the pixel is a patch pixel with depth, else neither; carrier = 1 where it is no
// patch pixel but has depth within one pixel (branch-free, one vectorised pass). Returns the carriers' count.
CLUTTERSEG_ROW_KERNEL int mark_roles(const int* __restrict labels, const uchar* __restrict has_depth,
                                     const uchar* __restrict near_depth, int count, int num_patches, int source,
                                     int neither, int* __restrict role, uchar* __restrict carrier) {
  int carriers = 0;
  for (int i = 0; i < count; ++i) {
    const int l = labels[i];
    role[i] = ((l > 0) & (l <= num_patches) & (has_depth[i] != 0)) ? source : neither;
    carrier[i] = (l == 0) & (near_depth[i] != 0);
    carriers += carrier[i];
  }
  return carriers;
}

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

  // What each pixel is to the propagation (one lookup per neighbour): a patch pixel with depth (a
  // source of seeds), a carrier of seeds (its index into `seeds`), or neither. Carriers are the non-patch
  // pixels with depth and the pixels without depth next to one (seeds cross holes of 1-2 px inside an
  // edge band, but do not flood the large regions without depth).
  constexpr int kSource = -2, kNeither = -1;
  // Every element of `role` is written row by row below: no zeroing (1.2 MB per 640x480 frame).
  const auto role = std::make_unique_for_overwrite<int[]>(static_cast<size_t>(total));
  struct Carrier {
    int i;
    std::int16_t x, y;
  };
  std::vector<Carrier> carriers;
  carriers.reserve(static_cast<size_t>(total) / 4);  // 8-20 % of the pixels on the dev sets
  // Row by row: the depth mask of rows y - 1, y, y + 1 (zero-padded: outside the image has no depth), the
  // 3x3 "depth nearby" of row y, then its roles and carriers, in one sweep over the frame.
  const int padded = width + 2;
  std::vector<uchar> depth_rows(3 * static_cast<size_t>(padded), 0), near(static_cast<size_t>(width)),
      carrier(static_cast<size_t>(width));
  uchar* up = depth_rows.data();
  uchar* mid = up + padded;
  uchar* down = mid + padded;
  mark_depth(&pts[0][0], width, mid + 1);
  for (int y = 0; y < height; ++y) {
    if (y + 1 < height) mark_depth(&pts[(y + 1) * width][0], width, down + 1);
    else std::fill(down, down + padded, uchar{0});
    mark_near_depth(up, mid, down, width, near.data());
    const int row = y * width;
    if (mark_roles(lab + row, mid + 1, near.data(), width, num_patches, kSource, kNeither, role.get() + row,
                   carrier.data()) > 0)
      for (int x = first_nonzero(carrier.data(), 0, width); x < width; x = first_nonzero(carrier.data(), x + 1, width)) {
        role[static_cast<size_t>(row + x)] = static_cast<int>(carriers.size());
        carriers.push_back({row + x, static_cast<std::int16_t>(x), static_cast<std::int16_t>(y)});
      }
    std::swap(up, mid);  // the rows move up by one: mid becomes up, down becomes mid
    std::swap(mid, down);
  }
  // Each set is cleared when the forward pass reaches its carrier: every set that pass reads (W, N, NE) belongs
  // to a carrier before it in raster order, so no pass over all of them first.
  const auto seeds = std::make_unique_for_overwrite<SeedSet[]>(carriers.size());

  // Two raster passes (forward: from W, N, NE; backward: from E, S, SW), as in a chamfer distance
  // transform: a seed reaches every pixel within r along a path the passes follow. NW and SE are left
  // out: W has already taken what its N holds in the same pass, so a seed at NW arrives through W (and
  // one at SE through E). A quarter fewer visits; on test63, 165 instead of 114 of 49,481 edge pixels
  // differ from the naive scan, and the scores on every dev and synthetic set are unchanged.
  const int r2 = r * r;
  // The pass is a compile-time constant, so the three offsets and their border tests are too.
  static constexpr int kFrom[2][3][2] = {{{-1, 0}, {0, -1}, {1, -1}}, {{1, 0}, {0, 1}, {-1, 1}}};
  auto gather = [&](const Carrier& c, auto pass) {
    constexpr auto& from = kFrom[decltype(pass)::value];
    const int x = c.x, y = c.y;
    SeedSet& own = seeds[static_cast<size_t>(role[static_cast<size_t>(c.i)])];
    if constexpr (decltype(pass)::value == 0) own.clear();
    const cv::Vec3f here = pts[c.i];
    const bool has_point = valid_point(here);
    auto offer = [&](std::uint32_t yx, int label) {
      const int sx = static_cast<int>(yx & 0xffff), sy = static_cast<int>(yx >> 16);
      const int dx = sx - x, dy = sy - y;
      own.offer(yx, label, [&] { return dx * dx + dy * dy <= r2; }, [&] {
        return has_point ? distance2(pts[sy * width + sx], here) : static_cast<float>(dx * dx + dy * dy);
      }, has_point ? d2_max : std::numeric_limits<float>::infinity());
    };
    auto visit = [&](int j, int xx, int yy) {
      const int neighbour = role[static_cast<size_t>(j)];
      if (neighbour == kSource) {
        const std::uint32_t yx = pack(xx, yy);
        if (!own.holds(yx)) offer(yx, lab[j]);
      } else if (neighbour >= 0) {
        const SeedSet& other = seeds[static_cast<size_t>(neighbour)];
        for (int s = 0; s < other.count; ++s)  // about 3 offers per carrier on osd-kinect, mostly new seeds
          if (!own.holds(other.yx[s])) offer(other.yx[s], other.label[s]);
      }
    };
    // Most carriers are inside the image: their neighbours need no border test (same order).
    if (x > 0 && y > 0 && x + 1 < width && y + 1 < height) {
      for (const auto& d : from) visit(c.i + d[1] * width + d[0], x + d[0], y + d[1]);
      return;
    }
    for (const auto& d : from) {
      const int xx = x + d[0], yy = y + d[1];
      if (xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
      visit(yy * width + xx, xx, yy);
    }
  };
  // The paper's rule on each reached pixel with depth: seeds within d_max. A carrier's seeds are final once the
  // backward pass has gathered them, so the rule runs there, while they are in cache (no third pass).
  int* assigned = out.labels.ptr<int>();
  out.assigned.reserve(carriers.size());
  out.contacts.reserve(carriers.size() / 4);  // pairs for 5-28 % of the carriers on the dev sets: no regrowth
  const auto decide = [&](const Carrier& c) {
    const int i = c.i;
    if (!valid_point(pts[i])) return;
    const SeedSet& own = seeds[static_cast<size_t>(role[static_cast<size_t>(i)])];
    int near[kMaxSeeds], count = 0, best = -1;
    for (int s = 0; s < own.count; ++s) {
      if (own.d2[s] >= d2_max) continue;
      near[count++] = s;
      if (best < 0 || own.d2[s] < own.d2[best] || (own.d2[s] == own.d2[best] && own.label[s] < own.label[best]))
        best = s;
    }
    if (best < 0) return;
    assigned[i] = own.label[best];
    out.assigned.push_back(i);
    for (int a = 0; a < count; ++a)
      for (int b = a + 1; b < count; ++b) {
        Seed sa = own.at(near[a]), sb = own.at(near[b]);
        if (sa.label > sb.label) std::swap(sa, sb);
        const auto pixel = [width](const Seed& s) { return static_cast<int>(s.yx >> 16) * width + static_cast<int>(s.yx & 0xffff); };
        out.contacts.push_back({sa.label - 1, sb.label - 1, pixel(sa), pixel(sb)});
      }
  };
  for (const Carrier& c : carriers) gather(c, std::integral_constant<int, 0>{});
  for (auto it = carriers.rbegin(); it != carriers.rend(); ++it) {
    gather(*it, std::integral_constant<int, 1>{});
    decide(*it);
  }
  // The contacts came in reverse raster order: reversed, each pair's come in raster order (one carrier gives a pair
  // at most once, so the order within a carrier does not matter once they are sorted by pair).
  std::reverse(out.contacts.begin(), out.contacts.end());
  std::stable_sort(out.contacts.begin(), out.contacts.end(),
                   [](const Contact& x, const Contact& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; });
  for (const Contact& c : out.contacts)
    if (out.adjacent.empty() || out.adjacent.back() != PatchPair(c.a, c.b)) out.adjacent.emplace_back(c.a, c.b);
  return out;
}

}  // namespace clutterseg
