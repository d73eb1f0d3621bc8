#include "clutterseg/coplanarity.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "clutterseg/occlusion.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/support.hpp"

namespace clutterseg {

namespace {

// Triangles thinner than this (smallest altitude) give a normal dominated by depth noise: with a few
// millimetres of noise per point, 2 cm keeps the triangle's normal within about 10 degrees.
constexpr float kMinAltitude = 0.02f;

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// One random stream per (seed, unordered pair), independent of the order the pairs are tested in.
std::uint64_t pair_seed(std::uint64_t seed, int id_a, int id_b) {
  const auto lo = static_cast<std::uint64_t>(std::min(id_a, id_b));
  const auto hi = static_cast<std::uint64_t>(std::max(id_a, id_b));
  return mix(seed ^ mix(0x636f706c616e6172ull ^ (lo << 32 | hi)));  // "coplanar" tag
}

Eigen::Vector3f point_at(const cv::Mat& points, int index) {
  const cv::Vec3f& p = points.ptr<cv::Vec3f>()[index];
  return {p[0], p[1], p[2]};
}

// A random valid point of the patch; bounded retries, then any valid pixel (patch pixels are valid).
Eigen::Vector3f random_point(const Patch& patch, const cv::Mat& points, std::mt19937_64& rng) {
  const auto n = static_cast<std::uint64_t>(patch.pixels.size());
  Eigen::Vector3f p = Eigen::Vector3f::Zero();
  for (int attempt = 0; attempt < 8; ++attempt) {
    p = point_at(points, patch.pixels[static_cast<size_t>(rng() % n)]);
    if (p.z() > 0) return p;
  }
  return p;
}

// Largest distance of a patch point from its centroid: bounds the gap between two patches from below.
float patch_radius(const Patch& patch, const cv::Mat& points) {
  float r2 = 0;
  for (int i : patch.pixels) {
    const Eigen::Vector3f p = point_at(points, i);
    if (p.z() > 0) r2 = std::max(r2, (p - patch.centroid).squaredNorm());
  }
  return std::sqrt(r2);
}

// Whether a patch takes part: flat by its histogram (the paper), or beyond the paper planar by its points
// although its histogram counts as curved (Params::Coplanarity::planar_share).
bool takes_part(const Patch& patch, const cv::Mat& points, const Params::Coplanarity& p) {
  if (!patch.curved) return true;
  // The plane through its centroid along its mean normal: noise on the normals averages out, and no fit
  // needs to read the points a second time.
  const Plane plane{patch.mean_normal, -patch.mean_normal.dot(patch.centroid)};
  return p.planar_share > 0 && mostly_within(patch.pixels, points, plane, p.planar_band, p.planar_share);
}

// Cheap necessary conditions, in order of cost: parallel, in each other's plane, both taking part
// (`part(patch)`), close enough (`radius(patch)`). The last two read a patch's pixels: asked for only
// when the angles pass.
template <typename TakesPart, typename Radius>
bool plausible(const Patch& a, const Patch& b, const Params::Coplanarity& p, TakesPart part, Radius radius) {
  if (a.pixels.empty() || b.pixels.empty()) return false;
  const float cos_max = static_cast<float>(std::cos(p.angle_deg * M_PI / 180.0));
  if (a.mean_normal.dot(b.mean_normal) < cos_max) return false;
  // The line between the centroids must lie within angle_deg of both planes (the same bound the
  // point triples check, applied once to the centroids).
  const Eigen::Vector3f d = b.centroid - a.centroid;
  const float len = d.norm();
  const float sin_max = static_cast<float>(std::sin(p.angle_deg * M_PI / 180.0));
  if (std::abs(a.mean_normal.dot(d)) > sin_max * len || std::abs(b.mean_normal.dot(d)) > sin_max * len) return false;
  return part(a) && part(b) && len - radius(a) - radius(b) <= p.max_gap;
}

// Paper g): point triples spanning both patches span the patches' plane, and the gap between them is
// occluded along random lines: little behind them, and (for a pair with a histogram-curved patch, beyond
// the paper) front_fraction in front.
bool spans_plane_and_occluded(const Patch& a, const Patch& b, const cv::Mat& points, const Camera& camera,
                              const Params::Coplanarity& p, std::uint64_t seed) {
  const double front_needed = a.curved || b.curved ? p.front_fraction : 0.0;
  std::mt19937_64 rng(pair_seed(seed, a.id, b.id));
  const Eigen::Vector3f mean = (a.mean_normal + b.mean_normal).normalized();
  const float cos_max = static_cast<float>(std::cos(p.angle_deg * M_PI / 180.0));

  // Two points from one patch and one from the other, alternating; thin triangles are redrawn
  // (bounded), and too few well-shaped triangles means the pair cannot be judged: not co-planar.
  int good = 0;
  const int attempts = 3 * p.triples;
  for (int t = 0; t < attempts && good < p.triples; ++t) {
    const Patch& two = (t % 2) ? b : a;
    const Patch& one = (t % 2) ? a : b;
    const Eigen::Vector3f p1 = random_point(two, points, rng), p2 = random_point(two, points, rng);
    const Eigen::Vector3f q = random_point(one, points, rng);
    const Eigen::Vector3f normal = (p2 - p1).cross(q - p1);
    const float longest = std::max({(p2 - p1).norm(), (q - p1).norm(), (q - p2).norm()});
    const float area2 = normal.norm();
    if (longest <= 0 || area2 / longest < kMinAltitude) continue;
    if (std::abs(normal.dot(mean)) < cos_max * area2) return false;  // paper: any deviation rejects
    ++good;
  }
  if (good < std::min(p.triples, 20)) return false;

  const int needed = static_cast<int>(std::ceil(p.lines_pass * p.lines - 1e-9));
  int failed = 0;
  for (int l = 0; l < p.lines; ++l) {
    const Eigen::Vector3f from = random_point(a, points, rng), to = random_point(b, points, rng);
    const GapView gap = view_gap(from, to, points, camera, p.behind_tolerance);
    failed += gap.behind > p.behind_fraction || gap.in_front < front_needed;
    if (failed > p.lines - needed) return false;  // too few lines left to pass: the answer is known
  }
  return true;
}

}  // namespace

bool coplanar(const Patch& a, const Patch& b, const cv::Mat& points, const Camera& camera,
              const Params::Coplanarity& params, std::uint64_t seed) {
  return plausible(a, b, params, [&](const Patch& patch) { return takes_part(patch, points, params); },
                   [&](const Patch& patch) { return patch_radius(patch, points); }) &&
         spans_plane_and_occluded(a, b, points, camera, params, seed);
}

std::vector<PatchPair> coplanar_pairs(const std::vector<Patch>& patches, const std::vector<PatchPair>& linked,
                                      const cv::Mat& points, const Camera& camera,
                                      const Params::Coplanarity& params, std::uint64_t seed) {
  std::vector<PatchPair> out;
  if (!params.enabled) return out;
  if (points.type() != CV_32FC3) throw Error("coplanar_pairs: points must be a CV_32FC3 image");
  std::vector<PatchPair> known = linked;
  for (auto& pair : known)
    if (pair.first > pair.second) std::swap(pair.first, pair.second);
  std::sort(known.begin(), known.end());

  // Per patch, once and only for the patches of a pair whose angles pass (most pairs do not): whether it
  // takes part (a plane fit, for a patch whose histogram counts as curved) and its radius (the table's
  // alone reads a third of the frame).
  const auto index_of = [&](const Patch& patch) { return static_cast<size_t>(&patch - patches.data()); };
  std::vector<signed char> part(patches.size(), -1);
  const auto part_of = [&](const Patch& patch) {
    signed char& t = part[index_of(patch)];
    if (t < 0) t = takes_part(patch, points, params) ? 1 : 0;
    return t == 1;
  };
  std::vector<float> radius(patches.size(), -1.f);
  const auto radius_of = [&](const Patch& patch) {
    float& r = radius[index_of(patch)];
    if (r < 0) r = patch_radius(patch, points);
    return r;
  };

  // Cheap rejections on all pairs first; the sampled test only on the few survivors.
  std::vector<PatchPair> candidates;
  for (size_t i = 0; i < patches.size(); ++i)
    for (size_t j = i + 1; j < patches.size(); ++j) {
      // Table pieces become one support object anyway (settle_table), and a link between the table and an
      // object is dropped (without_table_links): no table patch needs the test.
      if (patches[i].table || patches[j].table) continue;
      if (std::binary_search(known.begin(), known.end(), PatchPair(static_cast<int>(i), static_cast<int>(j)))) continue;
      if (plausible(patches[i], patches[j], params, part_of, radius_of))
        candidates.emplace_back(static_cast<int>(i), static_cast<int>(j));
    }

  // Each pair draws from its own seeded stream, so the result does not depend on the thread count.
  std::vector<char> accepted(candidates.size(), 0);
  parallel_for_rows(static_cast<int>(candidates.size()), [&](int begin, int end) {
    for (int c = begin; c < end; ++c) {
      const auto [i, j] = candidates[static_cast<size_t>(c)];
      accepted[static_cast<size_t>(c)] = spans_plane_and_occluded(
          patches[static_cast<size_t>(i)], patches[static_cast<size_t>(j)], points, camera, params, seed);
    }
  });
  for (size_t c = 0; c < candidates.size(); ++c)
    if (accepted[c]) out.push_back(candidates[c]);
  return out;
}

}  // namespace clutterseg
