// Paper e): cut-free neighbours. A plane through one patch that has many points of the other patch on
// both of its sides "cuts" it: a box side cuts the table it stands on, two faces of one box never cut
// each other (each lies behind the other's plane).
#include "clutterseg/cutfree.hpp"

#include "clutterseg/patches.hpp"
#include "clutterseg/support.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

namespace clutterseg {

namespace {

// SplitMix64 finaliser: independent streams for every (seed, pair, direction).
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

Eigen::Vector3f point_at(const cv::Mat& points, int index) {
  const cv::Vec3f& p = points.ptr<cv::Vec3f>()[index];
  return {p[0], p[1], p[2]};
}

// At most this many points of the other patch are classified per plane: a share is all we need.
constexpr size_t kMaxSamples = 500;

}  // namespace

bool one_side_of(const Patch& cutter, const Patch& other, const cv::Mat& points,
                 const Params::CutFree& params, std::uint64_t seed) {
  if (cutter.pixels.size() < 3 || other.pixels.empty() || params.planes <= 0) return true;
  std::vector<Eigen::Vector3f> samples;
  const size_t stride = std::max<size_t>(1, other.pixels.size() / sample_budget(kMaxSamples, points));
  for (size_t i = 0; i < other.pixels.size(); i += stride) {
    const Eigen::Vector3f q = point_at(points, other.pixels[i]);
    if (q.z() > 0) samples.push_back(q);
  }
  if (samples.empty()) return true;

  std::mt19937_64 rng(mix(seed));
  std::uniform_int_distribution<size_t> pick(0, cutter.pixels.size() - 1);
  const float band = static_cast<float>(params.band);
  // Tolerance relative to the smaller patch: a box at the back of a table leaves only a few percent
  // of the table behind its front plane, yet thousands of points, many more than noise at a shared
  // edge. (In sample units: the samples stand for all of other's points.)
  const double smaller = static_cast<double>(std::min(cutter.pixels.size(), other.pixels.size()));
  const double allowed = params.wrong_side_fraction * smaller * static_cast<double>(samples.size()) /
                         static_cast<double>(other.pixels.size());
  int planes = 0, accepted = 0;
  // Nearly collinear triples give no plane; they are drawn again, a bounded number of times.
  for (int attempt = 0; attempt < 4 * params.planes && planes < params.planes; ++attempt) {
    const Eigen::Vector3f a = point_at(points, cutter.pixels[pick(rng)]);
    const Eigen::Vector3f b = point_at(points, cutter.pixels[pick(rng)]);
    const Eigen::Vector3f c = point_at(points, cutter.pixels[pick(rng)]);
    const Eigen::Vector3f e1 = b - a, e2 = c - a;
    const Eigen::Vector3f n = e1.cross(e2);
    if (n.norm() <= 0.1f * e1.norm() * e2.norm() || n.norm() == 0.f) continue;  // angle < ~6 deg
    const Eigen::Vector3f unit = n.normalized();
    const float offset = -unit.dot(a);
    int above = 0, below = 0;
    for (const auto& q : samples) {
      const float d = unit.dot(q) + offset;
      above += d > band;
      below += d < -band;
    }
    ++planes;
    accepted += static_cast<double>(std::min(above, below)) <= allowed;
  }
  // A patch that yields no plane (a line of points) cannot cut anything.
  return planes == 0 || 2 * accepted > planes;
}

std::vector<PatchPair> cut_free_pairs(const std::vector<PatchPair>& adjacent,
                                      const std::vector<Patch>& patches, const cv::Mat& points,
                                      const Params::CutFree& params, std::uint64_t seed) {
  std::vector<PatchPair> kept;
  const double skip_cos = std::cos(params.skip_angle_deg * M_PI / 180.0);
  for (const auto& [a, b] : adjacent) {
    if (a < 0 || b < 0 || a >= static_cast<int>(patches.size()) || b >= static_cast<int>(patches.size()))
      throw Error("cut_free_pairs: patch index out of range");
    const Patch& pa = patches[static_cast<size_t>(a)];
    const Patch& pb = patches[static_cast<size_t>(b)];
    if (params.skip_similar && pa.mean_normal.dot(pb.mean_normal) > skip_cos) {
      kept.emplace_back(a, b);
      continue;
    }
    const std::uint64_t pair_seed = mix(seed ^ mix((static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b)));
    if (one_side_of(pa, pb, points, params, pair_seed) && one_side_of(pb, pa, points, params, pair_seed + 1))
      kept.emplace_back(a, b);
  }
  return kept;
}

int split_cut_patches(cv::Mat& edges, const std::vector<PatchPair>& adjacent, const std::vector<PatchPair>& linked,
                      const std::vector<Patch>& patches, const cv::Mat& patch_labels, const cv::Mat& points,
                      const Params::CutFree& params, int min_px, const Eigen::Vector3f& up) {
  if (params.split_share <= 0) return 0;
  const auto* pts = points.ptr<cv::Vec3f>();
  std::vector<std::uint8_t> split(patches.size(), 0);  // a patch is split once, at the first plane that cuts it
  std::vector<std::optional<std::optional<Plane>>> top_plane(patches.size());  // per cutter, fitted once: a flat
                                                                              // top's plane, or none
  cv::Mat below;  // pixels of the patches to split behind the cutting plane; made for the first split
  int marked = 0;
  // Whether `cutter`'s plane cuts `other` in two; marks other's far side in `below` if so.
  const auto cut = [&](const Patch& cutter, const Patch& other) {
    // Only a top face (within 30 deg of up) splits a side face (within 30 deg of vertical): an object
    // rests on a top. A box's side plane cuts the front of the box it stands on too (the front goes on
    // past it), but that front is one face.
    constexpr float kTopCos = 0.866f, kSideCos = 0.5f;
    if (cutter.mean_normal.dot(up) < kTopCos || std::abs(other.mean_normal.dot(up)) > kSideCos) return;
    if (static_cast<double>(other.pixels.size()) < 2.0 * min_px) return;
    auto& fitted = top_plane[static_cast<size_t>(cutter.id - 1)];
    if (!fitted) {
      Plane flat;
      const bool is_flat = fit_plane(cutter.pixels, points, flat) && mostly_within(cutter.pixels, points, flat, params.band, 0.9);
      fitted = is_flat ? std::optional<Plane>(flat) : std::nullopt;
    }
    if (!*fitted) return;
    const Plane& plane = **fitted;
    const size_t stride = std::max<size_t>(1, other.pixels.size() / sample_budget(2000, points));
    int above = 0, behind = 0, valid = 0;
    for (size_t k = 0; k < other.pixels.size(); k += stride) {
      const cv::Vec3f& q = pts[other.pixels[k]];
      if (!valid_point(q)) continue;
      const float d = plane.distance({q[0], q[1], q[2]}), tolerance = plane_tolerance(params.band, q[2]);
      ++valid;
      above += d > tolerance;
      behind += d < -tolerance;
    }
    if (valid == 0 || std::min(above, behind) < params.split_share * valid) return;
    if (below.empty()) below = cv::Mat(patch_labels.size(), CV_8U, cv::Scalar(0));
    for (int i : other.pixels)
      if (valid_point(pts[i]) && plane.distance({pts[i][0], pts[i][1], pts[i][2]}) < 0) {
        below.ptr<uchar>()[i] = 255;
        ++marked;
      }
    split[static_cast<size_t>(other.id - 1)] = 1;
  };
  for (const PatchPair& pair : adjacent) {
    if (std::binary_search(linked.begin(), linked.end(), pair)) continue;
    const Patch& a = patches[static_cast<size_t>(pair.first)];
    const Patch& b = patches[static_cast<size_t>(pair.second)];
    if (!split[static_cast<size_t>(pair.second)]) cut(a, b);
    if (!split[static_cast<size_t>(pair.first)]) cut(b, a);
  }
  if (marked > 0) separate_marked(edges, below, patch_labels);
  return marked;
}

}  // namespace clutterseg
