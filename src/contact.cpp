#include "clutterseg/contact.hpp"

#include <algorithm>
#include <cmath>

namespace clutterseg {

namespace {

// Contacts read per pair: the mean of this many is as good as of all of them.
constexpr int kMaxSamples = 64;
// A pair seen by fewer contacts than this is not judged (one noisy pixel pair is no crease).
constexpr int kMinSamples = 3;

}  // namespace

std::vector<PairJunction> classify_junctions(const std::vector<Contact>& contacts, const cv::Mat& points,
                                             const NormalPlanes& normals, const Params::Convexity& params) {
  if (points.type() != CV_32FC3 || normals[0].size() != points.size())
    throw Error("classify_junctions: points must be CV_32FC3 and normals of the same size");
  const auto* pts = points.ptr<cv::Vec3f>();
  const float* nx = normals[0].ptr<float>();
  const float* ny = normals[1].ptr<float>();
  const float* nz = normals[2].ptr<float>();
  const auto normal = [&](int i) { return Eigen::Vector3f(nx[i], ny[i], nz[i]); };
  const auto point = [&](int i) { return Eigen::Vector3f(pts[i][0], pts[i][1], pts[i][2]); };
  std::vector<PairJunction> out;
  for (size_t begin = 0; begin < contacts.size();) {
    size_t end = begin;
    while (end < contacts.size() && contacts[end].a == contacts[begin].a && contacts[end].b == contacts[begin].b) ++end;
    PairJunction j;
    j.pair = {contacts[begin].a, contacts[begin].b};
    const size_t stride = std::max<size_t>(1, (end - begin) / kMaxSamples);
    double sum = 0;
    for (size_t k = begin; k < end; k += stride) {
      const Contact& c = contacts[k];
      const Eigen::Vector3f d = point(c.pixel_a) - point(c.pixel_b);
      const Eigen::Vector3f dn = normal(c.pixel_a) - normal(c.pixel_b);
      const float length = d.norm();
      if (!(length > 1e-4f) || !std::isfinite(dn.squaredNorm())) continue;  // the same point, or no normal
      sum += dn.dot(d) / length;
      ++j.samples;
    }
    if (j.samples > 0) j.convexity = static_cast<float>(sum / j.samples);
    if (j.samples >= kMinSamples)
      j.kind = j.convexity > params.tolerance ? Junction::Convex
             : j.convexity < -params.tolerance ? Junction::Concave : Junction::Flat;
    out.push_back(j);
    begin = end;
  }
  return out;
}

}  // namespace clutterseg
