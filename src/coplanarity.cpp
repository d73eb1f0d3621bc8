#include "clutterseg/coplanarity.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "clutterseg/occlusion.hpp"
#include "clutterseg/parallel.hpp"

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

// Cheap necessary conditions, in order of cost: flat, parallel, in each other's plane, close enough.
// The radii are asked for last (`radius(patch)`): reading a patch's pixels is the costly part.
template <typename Radius>
bool plausible(const Patch& a, const Patch& b, const Params::Coplanarity& p, Radius radius) {
  if (a.curved || b.curved || a.pixels.empty() || b.pixels.empty()) return false;
  const float cos_max = static_cast<float>(std::cos(p.angle_deg * M_PI / 180.0));
  if (a.mean_normal.dot(b.mean_normal) < cos_max) return false;
  // The line between the centroids must lie within angle_deg of both planes (the same bound the
  // point triples check, applied once to the centroids).
  const Eigen::Vector3f d = b.centroid - a.centroid;
  const float len = d.norm();
  const float sin_max = static_cast<float>(std::sin(p.angle_deg * M_PI / 180.0));
  if (std::abs(a.mean_normal.dot(d)) > sin_max * len || std::abs(b.mean_normal.dot(d)) > sin_max * len) return false;
  return len - radius(a) - radius(b) <= p.max_gap;
}

// Paper g): point triples spanning both patches span the patches' plane, and the gap between them is
// occluded along random lines.
bool spans_plane_and_occluded(const Patch& a, const Patch& b, const cv::Mat& points, const Camera& camera,
                              const Params::Coplanarity& p, std::uint64_t seed) {
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

  int passed = 0;
  for (int l = 0; l < p.lines; ++l) {
    const Eigen::Vector3f from = random_point(a, points, rng), to = random_point(b, points, rng);
    if (behind_fraction(from, to, points, camera, p.behind_tolerance) <= p.behind_fraction) ++passed;
  }
  return passed >= static_cast<int>(std::ceil(p.lines_pass * p.lines - 1e-9));
}

}  // namespace

bool coplanar(const Patch& a, const Patch& b, const cv::Mat& points, const Camera& camera,
              const Params::Coplanarity& params, std::uint64_t seed) {
  if (a.curved || b.curved || a.pixels.empty() || b.pixels.empty()) return false;
  return plausible(a, b, params, [&](const Patch& patch) { return patch_radius(patch, points); }) &&
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

  std::vector<int> flat;
  for (size_t i = 0; i < patches.size(); ++i)
    if (!patches[i].curved && !patches[i].pixels.empty()) flat.push_back(static_cast<int>(i));
  // A patch's radius once, and only for the patches of a pair that passes the other tests (most pairs do
  // not; the table's radius alone reads a third of the frame).
  std::vector<float> radius(patches.size(), -1.f);
  const auto radius_of = [&](const Patch& patch) {
    float& r = radius[static_cast<size_t>(&patch - patches.data())];
    if (r < 0) r = patch_radius(patch, points);
    return r;
  };

  // Cheap rejections on all pairs first; the sampled test only on the few survivors.
  std::vector<PatchPair> candidates;
  for (size_t x = 0; x < flat.size(); ++x)
    for (size_t y = x + 1; y < flat.size(); ++y) {
      const int i = flat[x], j = flat[y];
      if (std::binary_search(known.begin(), known.end(), PatchPair(i, j))) continue;
      if (plausible(patches[static_cast<size_t>(i)], patches[static_cast<size_t>(j)], params, radius_of))
        candidates.emplace_back(i, j);
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
