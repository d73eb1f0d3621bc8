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

}  // namespace clutterseg
