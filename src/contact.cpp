#include "clutterseg/contact.hpp"

#include <algorithm>
#include <cmath>
#include <span>

namespace clutterseg {

namespace {

// Contacts read per pair: the mean of this many is as good as of all of them.
constexpr int kMaxSamples = 64;
// A pair seen by few contacts is judged with a wider margin: the tolerance times kFewSamples / samples
// (one noisy pixel pair must show a crease three times as sharp).
constexpr int kFewSamples = 3;
// Faces whose mean normals are within this angle are parallel for the offset test (Params::Convexity::
// step_offset): a crease between them is at most this sharp, so a step is what their contacts can show.
constexpr double kParallelDeg = 10;

}  // namespace

std::vector<PairJunction> classify_junctions(const std::vector<Contact>& contacts, const cv::Mat& points,
                                             const NormalPlanes& normals, const Params::Convexity& params,
                                             std::span<const Patch> patches) {
  if (points.type() != CV_32FC3 || normals[0].size() != points.size())
    throw Error("classify_junctions: points must be CV_32FC3 and normals of the same size");
  const auto* pts = points.ptr<cv::Vec3f>();
  const float* nx = normals[0].ptr<float>();
  const float* ny = normals[1].ptr<float>();
  const float* nz = normals[2].ptr<float>();
  const auto normal = [&](int i) { return Eigen::Vector3f(nx[i], ny[i], nz[i]); };
  const auto point = [&](int i) { return Eigen::Vector3f(pts[i][0], pts[i][1], pts[i][2]); };
  const float parallel_cos = static_cast<float>(std::cos(kParallelDeg * M_PI / 180.0));
  std::vector<PairJunction> out;
  for (size_t begin = 0; begin < contacts.size();) {
    size_t end = begin;
    while (end < contacts.size() && contacts[end].a == contacts[begin].a && contacts[end].b == contacts[begin].b) ++end;
    PairJunction j;
    j.pair = {contacts[begin].a, contacts[begin].b};
    const size_t stride = std::max<size_t>(1, (end - begin) / kMaxSamples);
    // The offset test's face normal: the bisector of the two patches' mean normals, when they are parallel.
    Eigen::Vector3f face = Eigen::Vector3f::Zero();
    if (params.step_offset > 0 && static_cast<size_t>(j.pair.second) < patches.size()) {
      const Eigen::Vector3f& na = patches[static_cast<size_t>(j.pair.first)].mean_normal;
      const Eigen::Vector3f& nb = patches[static_cast<size_t>(j.pair.second)].mean_normal;
      if (na.dot(nb) >= parallel_cos) face = (na + nb).normalized();
    }
    double sum = 0, out_of_plane = 0, offset = 0, depth = 0;
    for (size_t k = begin; k < end; k += stride) {
      const Contact& c = contacts[k];
      const Eigen::Vector3f d = point(c.pixel_a) - point(c.pixel_b);
      const Eigen::Vector3f dn = normal(c.pixel_a) - normal(c.pixel_b);
      const Eigen::Vector3f mean_normal = normal(c.pixel_a) + normal(c.pixel_b);
      const float length = d.norm();
      if (!(length > 1e-4f) || !(mean_normal.norm() > 1e-3f)) continue;  // the same point, or no normal
      sum += dn.dot(d) / length;
      out_of_plane += std::abs(mean_normal.normalized().dot(d)) / length;
      offset += face.dot(d);
      depth += 0.5 * (pts[c.pixel_a][2] + pts[c.pixel_b][2]);
      ++j.samples;
    }
    if (j.samples > 0) {
      j.convexity = static_cast<float>(sum / j.samples);
      j.step = static_cast<float>(out_of_plane / j.samples);
    }
    const double few = std::max(1.0, static_cast<double>(kFewSamples) / std::max(1, j.samples));
    const double margin = params.tolerance * few;
    // Parallel faces offset along their normal: a step, whatever the contact normals say (near the band
    // they are smoothed across the step's own small faces and read as a crease of either sign).
    const double z = j.samples > 0 ? depth / j.samples : 0;
    const bool offset_step = face.squaredNorm() > 0 && j.samples > 0 &&
                             std::abs(offset / j.samples) > params.step_offset * few * std::max(1.0, z * z);
    if (j.samples > 0)
      j.kind = offset_step ? Junction::Step : j.convexity > margin ? Junction::Convex : j.convexity < -margin ? Junction::Concave
             : j.step > params.step ? Junction::Step : Junction::Flat;
    out.push_back(j);
    begin = end;
  }
  return out;
}

const PairJunction* junction_of(const std::vector<PairJunction>& junctions, int a, int b) {
  const PatchPair pair(std::min(a, b), std::max(a, b));
  const auto j = std::lower_bound(junctions.begin(), junctions.end(), pair,
                                  [](const PairJunction& x, const PatchPair& p) { return x.pair < p; });
  return j != junctions.end() && j->pair == pair ? &*j : nullptr;
}

std::vector<PatchPair> contacts_across_tops(const std::vector<PairJunction>& junctions, std::span<const Patch> patches,
                                            const cv::Mat& points, const Eigen::Vector3f& up,
                                            const Params::Convexity& params) {
  std::vector<PatchPair> out;
  if (params.top_angle_deg <= 0 || points.type() != CV_32FC3) return out;
  const auto* pts = points.ptr<cv::Vec3f>();
  const float top_cos = static_cast<float>(std::cos(params.top_angle_deg * M_PI / 180.0));
  // Whether `side` (+1 above, -1 below) holds 90 % of a patch's points, the plane through the top face's
  // centroid along its mean normal (a noisy top's normals need not fit a plane).
  const auto on_side = [&](const Patch& patch, const Patch& top, int side) {
    constexpr size_t kSamples = 200;
    constexpr double kTolerance = 0.005, kShare = 0.9;
    const size_t stride = std::max<size_t>(1, patch.pixels.size() / kSamples);
    int on = 0, all = 0;
    for (size_t k = 0; k < patch.pixels.size(); k += stride) {
      const cv::Vec3f& q = pts[patch.pixels[k]];
      if (!valid_point(q)) continue;
      const float height = top.mean_normal.dot(Eigen::Vector3f(q[0], q[1], q[2]) - top.centroid);
      const double z = q[2];
      ++all;
      on += side * height > -kTolerance * std::max(1.0, z * z);
    }
    return all > 0 && on >= kShare * all;
  };
  const int n = static_cast<int>(patches.size());
  for (const PairJunction& resting : junctions) {
    if (resting.kind != Junction::Concave) continue;
    for (const auto& [a, b] : {resting.pair, PatchPair(resting.pair.second, resting.pair.first)}) {  // a rests on b
      if (a < 0 || b < 0 || a >= n || b >= n) continue;
      const Patch& top = patches[static_cast<size_t>(b)];
      // The top face's normal faces the camera; "up" may point either way along the table's normal.
      if (std::abs(top.mean_normal.dot(up)) < top_cos || !on_side(patches[static_cast<size_t>(a)], top, +1)) continue;
      for (const PairJunction& edge : junctions) {  // b's side faces: convex edges, below b's plane
        if (edge.kind != Junction::Convex || (edge.pair.first != b && edge.pair.second != b)) continue;
        const int c = edge.pair.first == b ? edge.pair.second : edge.pair.first;
        if (c == a || c < 0 || c >= n) continue;
        const PairJunction* touching = junction_of(junctions, a, c);
        if (!touching || touching->kind == Junction::Concave || touching->kind == Junction::Step) continue;
        if (on_side(patches[static_cast<size_t>(c)], top, -1)) out.emplace_back(std::min(a, c), std::max(a, c));
      }
    }
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace clutterseg
