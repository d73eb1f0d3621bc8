#include "clutterseg/curvature.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

#include "clutterseg/occlusion.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/patches.hpp"

namespace clutterseg {

namespace {

// |correlation| between normal and position along the direction the normals turn in, above which
// the sign decides convexity. An ideal cylinder or sphere gives exactly +-1; noise and a flat part
// pull it towards 0.
constexpr double kConvexityCorrelation = 0.5;
constexpr int kMinPeakPoints = 3;            // fewest peak-bin points per patch for a line fit
// Large patches are subsampled on a fixed pixel stride (deterministic) for the statistics below.
constexpr size_t kConvexitySamples = 1024;  // pixels used at most for the moments of a patch
constexpr size_t kBinnedSamples = 2048;     // pixels used at most for a patch's peak-bin points

Eigen::Vector3f vec(const cv::Vec3f& v) { return {v[0], v[1], v[2]}; }

int histogram_side(const std::vector<float>& histogram) {
  return static_cast<int>(std::lround(std::sqrt(static_cast<double>(histogram.size()))));
}

cv::Rect grown(const cv::Rect& r, int by) { return {r.x - by, r.y - by, r.width + 2 * by, r.height + 2 * by}; }

// on_edge[x] = 1 where row[x] differs from one of its 8 neighbours (rows up and down), for 0 < x < cols - 1.
CLUTTERSEG_ROW_KERNEL void differs_from_neighbours(const int* __restrict up, const int* __restrict row,
                                                   const int* __restrict down, int cols, uchar* __restrict on_edge) {
  for (int x = 1; x + 1 < cols; ++x) {
    const int id = row[x];
    on_edge[x] = (up[x - 1] != id) | (up[x] != id) | (up[x + 1] != id) | (row[x - 1] != id) | (row[x + 1] != id) |
                 (down[x - 1] != id) | (down[x] != id) | (down[x + 1] != id);
  }
}

// Per label (index id - 1, only where `wanted`), the pixels with an 8-neighbour outside the label:
// one pass over rows [y_begin, y_end), which must hold every wanted pixel. The two closest pixels of two
// disjoint patches are boundary pixels: from an interior pixel, a step towards the other patch stays
// inside and gets closer.
std::vector<std::vector<cv::Point>> boundaries(const cv::Mat& labels, const std::vector<char>& wanted, int y_begin,
                                               int y_end) {
  std::vector<std::vector<cv::Point>> out(wanted.size());
  const int max_id = static_cast<int>(wanted.size()), cols = labels.cols;
  std::vector<uchar> on_edge(static_cast<size_t>(cols), 1);  // image border pixels stay 1
  for (int y = std::max(0, y_begin); y < std::min(labels.rows, y_end); ++y) {
    const int* row = labels.ptr<int>(y);
    const bool inner_row = y > 0 && y + 1 < labels.rows;
    if (inner_row) differs_from_neighbours(labels.ptr<int>(y - 1), row, labels.ptr<int>(y + 1), cols, on_edge.data());
    // Inside the image only the marked pixels, found eight bytes at a time (most pixels are interior).
    for (int x = inner_row ? first_nonzero(on_edge.data(), 0, cols) : 0; x < cols;
         x = inner_row ? first_nonzero(on_edge.data(), x + 1, cols) : x + 1) {
      const int id = row[x];
      if (id > 0 && id <= max_id && wanted[static_cast<size_t>(id - 1)])
        out[static_cast<size_t>(id - 1)].emplace_back(x, y);
    }
  }
  return out;
}

// Some pixel of a lies within `gap` pixels of some pixel of b (boundaries of both), via a grid of
// gap-sized cells over b's boundary: O(|boundary a| + |boundary b|).
bool within_gap(const std::vector<cv::Point>& a, const std::vector<cv::Point>& b, int gap, cv::Size image) {
  if (a.empty() || b.empty()) return false;
  const int cols = image.width / gap + 1, rows = image.height / gap + 1;
  std::vector<int> start(static_cast<size_t>(cols * rows) + 1, 0);
  auto cell = [&](const cv::Point& p) { return (p.y / gap) * cols + p.x / gap; };
  for (const auto& p : b) ++start[static_cast<size_t>(cell(p)) + 1];
  for (size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
  std::vector<cv::Point> sorted(b.size());
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (const auto& p : b) sorted[static_cast<size_t>(fill[static_cast<size_t>(cell(p))]++)] = p;
  const int gap2 = gap * gap;
  for (const auto& p : a) {
    const int cx = p.x / gap, cy = p.y / gap;
    for (int y = std::max(0, cy - 1); y <= std::min(rows - 1, cy + 1); ++y)
      for (int x = std::max(0, cx - 1); x <= std::min(cols - 1, cx + 1); ++x)
        for (int k = start[static_cast<size_t>(y * cols + x)]; k < start[static_cast<size_t>(y * cols + x) + 1]; ++k) {
          const cv::Point d = sorted[static_cast<size_t>(k)] - p;
          if (d.x * d.x + d.y * d.y <= gap2) return true;
        }
  }
  return false;
}

// A patch's pixels (at most kBinnedSamples of them, on a fixed stride) grouped by the histogram bin
// of their normal (counting sort), built once per patch so each pair only reads the bin it needs.
struct BinnedPixels {
  std::vector<int> start;   // bins*bins + 1 offsets into `pixels`
  std::vector<int> pixels;  // valid pixels, ordered by bin

  BinnedPixels(const Patch& patch, int bins, const cv::Mat& points, const NormalPlanes& normals) {
    const auto* pts = points.ptr<cv::Vec3f>();
    const float *nx = normals[0].ptr<float>(), *ny = normals[1].ptr<float>();
    const size_t stride = std::max<size_t>(1, patch.pixels.size() / sample_budget(kBinnedSamples, points));
    std::vector<int> sampled, bin_of;
    start.assign(static_cast<size_t>(bins * bins) + 1, 0);
    for (size_t k = 0; k < patch.pixels.size(); k += stride) {
      const int i = patch.pixels[k];
      if (!(pts[i][2] > 0)) continue;
      sampled.push_back(i);
      bin_of.push_back(normal_bin(nx[i], ny[i], bins));
      ++start[static_cast<size_t>(bin_of.back()) + 1];
    }
    for (size_t b = 1; b < start.size(); ++b) start[b] += start[b - 1];
    pixels.resize(sampled.size());
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (size_t k = 0; k < sampled.size(); ++k) pixels[static_cast<size_t>(fill[static_cast<size_t>(bin_of[k])]++)] = sampled[k];
  }

  std::vector<Eigen::Vector3f> points_in(int bin, const cv::Mat& points) const {
    const auto* pts = points.ptr<cv::Vec3f>();
    std::vector<Eigen::Vector3f> out;
    for (int k = start[static_cast<size_t>(bin)]; k < start[static_cast<size_t>(bin) + 1]; ++k)
      out.push_back(vec(pts[pixels[static_cast<size_t>(k)]]));
    return out;
  }
};

struct Line {
  Eigen::Vector3f point, direction;
  float distance(const Eigen::Vector3f& x) const { return (x - point - (x - point).dot(direction) * direction).norm(); }
  float position(const Eigen::Vector3f& x) const { return (x - point).dot(direction); }
};

Line fit_line(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto* set : {&a, &b})
    for (const auto& p : *set) mean += p.cast<double>();
  mean /= static_cast<double>(a.size() + b.size());
  // The six sums of the scatter matrix as scalars: Eigen's `cov += d * d.transpose()` went through the
  // stack for every point, a stalled store-to-load that was most of this stage's time (same sums).
  double xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  for (const auto* set : {&a, &b})
    for (const auto& p : *set) {
      const Eigen::Vector3d d = p.cast<double>() - mean;
      xx += d.x() * d.x(); xy += d.x() * d.y(); xz += d.x() * d.z();
      yy += d.y() * d.y(); yz += d.y() * d.z(); zz += d.z() * d.z();
    }
  Eigen::Matrix3d cov;
  cov << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  return {mean.cast<float>(), eig.eigenvectors().col(2).normalized().cast<float>()};
}

float rms_distance(const Line& line, const std::vector<Eigen::Vector3f>& set) {
  double sum = 0;
  for (const auto& p : set) sum += static_cast<double>(line.distance(p)) * line.distance(p);
  return static_cast<float>(std::sqrt(sum / static_cast<double>(set.size())));
}

// Paper h), occluded curved object: the points of the bin both histograms share most (for a
// cylinder: a generator line on each part) lie on one 3D line, and the stretch of that line between
// the two parts is hidden by something in front, not open to the background.
bool aligned_and_occluded(const Patch& a, const BinnedPixels& binned_a, const Patch& b, const BinnedPixels& binned_b,
                          const cv::Mat& points, const Camera& camera, const Params& params) {
  int peak = 0;
  float best = -1;
  for (size_t k = 0; k < a.histogram.size(); ++k) {
    const float shared = std::min(a.histogram[k], b.histogram[k]);
    if (shared > best) { best = shared; peak = static_cast<int>(k); }
  }
  const auto pa = binned_a.points_in(peak, points), pb = binned_b.points_in(peak, points);
  if (static_cast<int>(pa.size()) < kMinPeakPoints || static_cast<int>(pb.size()) < kMinPeakPoints) return false;
  const Line line = fit_line(pa, pb);
  // Each part must follow the line, so a large part cannot hide a small one that is off the line.
  const auto fit = static_cast<float>(params.curvature.line_fit);
  if (rms_distance(line, pa) > fit || rms_distance(line, pb) > fit) return false;

  float a_lo = INFINITY, a_hi = -INFINITY, b_lo = INFINITY, b_hi = -INFINITY;
  for (const auto& p : pa) { const float t = line.position(p); a_lo = std::min(a_lo, t); a_hi = std::max(a_hi, t); }
  for (const auto& p : pb) { const float t = line.position(p); b_lo = std::min(b_lo, t); b_hi = std::max(b_hi, t); }
  float from, to;
  if (a_hi < b_lo) { from = a_hi; to = b_lo; }
  else if (b_hi < a_lo) { from = b_hi; to = a_lo; }
  else return false;  // side by side along the line: nothing between them to be an occluder
  const Eigen::Vector3f start = line.point + from * line.direction, end = line.point + to * line.direction;
  return behind_fraction(start, end, points, camera, params.coplanarity.behind_tolerance) <=
         params.coplanarity.behind_fraction;
}

// Where a curved patch's normal lines meet: the centre of a sphere, or the axis of a cylinder (when the
// normals all lie across one direction). The walls of one cup or bowl share it; two objects side by
// side do not. Least squares over the lines p + t n: sum (I - n n^T) c = sum (I - n n^T) p.
struct CurvatureCentre {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  // zero for a point
  double radius = 0;                               // mean distance of the patch's points to the centre
  bool valid = false;

  double distance(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d d = x - point;
    return (d - d.dot(axis) * axis).norm();
  }
};

// A direction whose eigenvalue is below this share of the largest one carries no information: the normals
// barely turn across it (a cylinder's axis; for the second direction too, a plane: no centre).
constexpr double kFlatDirection = 0.08;
constexpr size_t kCentreSamples = 256;  // pixels used at most for a patch's centre: a least-squares point

CurvatureCentre curvature_centre(const Patch& patch, const cv::Mat& points, const NormalPlanes& normals) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const float *nx = normals[0].ptr<float>(), *ny = normals[1].ptr<float>(), *nz = normals[2].ptr<float>();
  const size_t stride = std::max<size_t>(1, patch.pixels.size() / sample_budget(kCentreSamples, points));
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> sample;
  for (size_t k = 0; k < patch.pixels.size(); k += stride) {
    const int i = patch.pixels[k];
    const Eigen::Vector3d n(nx[i], ny[i], nz[i]);
    if (!(pts[i][2] > 0) || n.squaredNorm() < 0.5) continue;
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - n * n.transpose();
    sample.push_back(vec(pts[i]).cast<double>());
    a += across;
    b += across * sample.back();
  }
  CurvatureCentre centre;
  if (sample.size() < 10) return centre;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(a);  // eigenvalues ascending
  const Eigen::Vector3d lambda = eig.eigenvalues();
  if (!(lambda(2) > 0) || lambda(1) < kFlatDirection * lambda(2)) return centre;
  const int first = lambda(0) < kFlatDirection * lambda(2) ? 1 : 0;  // 1: a cylinder, its axis dropped
  for (int k = first; k < 3; ++k) centre.point += eig.eigenvectors().col(k).dot(b) / lambda(k) * eig.eigenvectors().col(k);
  if (first == 1) centre.axis = eig.eigenvectors().col(0);
  for (const auto& x : sample) centre.radius += centre.distance(x);
  centre.radius /= static_cast<double>(sample.size());
  centre.valid = std::isfinite(centre.radius);
  return centre;
}

// The walls of one open object: the inner wall's centre lies on the outer wall's (a point or its axis)
// within `share` of the outer wall's radius, and the inner wall is not the larger.
bool concentric(const CurvatureCentre& outer, const CurvatureCentre& inner, double share) {
  if (!outer.valid || !inner.valid || inner.radius > outer.radius * (1 + share)) return false;
  const double d = outer.axis.isZero() && !inner.axis.isZero() ? inner.distance(outer.point) : outer.distance(inner.point);
  return d <= share * outer.radius;
}

// Two parts of one surface: both centres a point (a sphere) or both an axis (a cylinder), each on the other
// within `share` of the larger radius, and the radii within that share of each other.
bool one_surface(const CurvatureCentre& a, const CurvatureCentre& b, double share) {
  if (!a.valid || !b.valid || a.axis.isZero() != b.axis.isZero()) return false;
  const double r = std::max(a.radius, b.radius);
  return std::min(a.radius, b.radius) >= (1 - share) * r && a.distance(b.point) <= share * r &&
         b.distance(a.point) <= share * r;
}

// Each patch's convexity and centre of curvature, computed the first time a rule asks (most pairs are decided
// without them).
class PatchShapes {
 public:
  PatchShapes(const std::vector<Patch>& patches, const cv::Mat& points, const NormalPlanes& normals)
      : patches_(patches), points_(points), normals_(normals), convex_(patches.size(), kUnknown), centres_(patches.size()) {}
  int convexity_of(int i) {
    int& c = convex_[static_cast<size_t>(i)];
    const Patch& patch = patches_[static_cast<size_t>(i)];
    if (c == kUnknown) c = convexity(patch, points_, normals_, histogram_side(patch.histogram));
    return c;
  }
  const CurvatureCentre& centre_of(int i) {
    auto& c = centres_[static_cast<size_t>(i)];
    if (!c) c = curvature_centre(patches_[static_cast<size_t>(i)], points_, normals_);
    return *c;
  }

 private:
  static constexpr int kUnknown = 2;
  const std::vector<Patch>& patches_;
  const cv::Mat& points_;
  const NormalPlanes& normals_;
  std::vector<int> convex_;
  std::vector<std::optional<CurvatureCentre>> centres_;
};

}  // namespace

double histogram_similarity(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) throw Error("histogram_similarity: histograms differ in size");
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += std::min(a[k], b[k]);
  return s;
}

int convexity(const Patch& patch, const cv::Mat& points, const NormalPlanes& normals, int bins) {
  // Physically: on a convex surface the (outward, camera-facing) normal turns the way one walks,
  // dn = S dp with a positive shape operator S; on a concave one it turns against. We find the
  // direction e in which the normals vary most (the major axis of the histogram blob, paper Eq. 4)
  // and correlate n.e with p.e over the patch: the sign is the sign of the curvature along e.
  // One pass of first and second moments; large patches are subsampled on a fixed stride.
  const auto* pts = points.ptr<cv::Vec3f>();
  const float *nx = normals[0].ptr<float>(), *ny = normals[1].ptr<float>(), *nz = normals[2].ptr<float>();
  const size_t stride = std::max<size_t>(1, patch.pixels.size() / sample_budget(kConvexitySamples, points));
  // Sums as plain scalars (Eigen's outer-product updates went through the stack for every pixel).
  double n0 = 0, n1 = 0, n2 = 0, p0 = 0, p1 = 0, p2 = 0;
  double nn[6] = {}, pp[6] = {}, np[9] = {};  // nn, pp: upper triangles, row by row; np: row-major
  double count = 0;
  for (size_t k = 0; k < patch.pixels.size(); k += stride) {
    const int i = patch.pixels[k];
    if (!(pts[i][2] > 0) || (nx[i] == 0 && ny[i] == 0 && nz[i] == 0)) continue;
    const double a0 = nx[i], a1 = ny[i], a2 = nz[i];
    const double b0 = pts[i][0], b1 = pts[i][1], b2 = pts[i][2];
    n0 += a0; n1 += a1; n2 += a2; p0 += b0; p1 += b1; p2 += b2;
    nn[0] += a0 * a0; nn[1] += a0 * a1; nn[2] += a0 * a2; nn[3] += a1 * a1; nn[4] += a1 * a2; nn[5] += a2 * a2;
    pp[0] += b0 * b0; pp[1] += b0 * b1; pp[2] += b0 * b2; pp[3] += b1 * b1; pp[4] += b1 * b2; pp[5] += b2 * b2;
    np[0] += a0 * b0; np[1] += a0 * b1; np[2] += a0 * b2; np[3] += a1 * b0; np[4] += a1 * b1; np[5] += a1 * b2;
    np[6] += a2 * b0; np[7] += a2 * b1; np[8] += a2 * b2;
    ++count;
  }
  if (count < 10) return 0;
  const auto symmetric = [](const double* u) {
    Eigen::Matrix3d m;
    m << u[0], u[1], u[2], u[1], u[3], u[4], u[2], u[4], u[5];
    return m;
  };
  const Eigen::Vector3d sn(n0, n1, n2), sp(p0, p1, p2);
  const Eigen::Matrix3d snn = symmetric(nn), spp = symmetric(pp);
  const Eigen::Matrix3d snp = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(np);
  const Eigen::Vector3d n_mean = sn / count, p_mean = sp / count;
  const Eigen::Matrix3d n_cov = snn / count - n_mean * n_mean.transpose();
  const Eigen::Matrix3d np_cov = snp / count - n_mean * p_mean.transpose();
  const Eigen::Matrix3d p_cov = spp / count - p_mean * p_mean.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(n_cov);
  const Eigen::Vector3d e = eig.eigenvectors().col(2);
  // Normals that vary by less than a histogram bin along e: no curvature to judge.
  if (2 * std::sqrt(std::max(0.0, eig.eigenvalues()(2))) < 2.0 / std::max(1, bins)) return 0;
  const double var_n = e.dot(n_cov * e), var_p = e.dot(p_cov * e), cov_np = e.dot(np_cov * e);
  if (var_n <= 0 || var_p <= 0) return 0;
  const double correlation = cov_np / std::sqrt(var_n * var_p);
  return correlation > kConvexityCorrelation ? 1 : correlation < -kConvexityCorrelation ? -1 : 0;
}

std::optional<Cylinder> fit_cylinder(const std::vector<int>& pixels, const cv::Mat& points, const NormalPlanes& normals) {
  constexpr double kAcrossAxis = 0.1, kTurning = 0.02, kMaxRadius = 0.3;  // sin^2 shares of the largest eigenvalue
  const auto* pts = points.ptr<cv::Vec3f>();
  const float *nx = normals[0].ptr<float>(), *ny = normals[1].ptr<float>(), *nz = normals[2].ptr<float>();
  const size_t stride = std::max<size_t>(1, pixels.size() / 512);
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> sample;  // (point, normal)
  Eigen::Matrix3d spread = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < pixels.size(); k += stride) {
    const int i = pixels[k];
    const Eigen::Vector3d n(nx[i], ny[i], nz[i]);
    if (!valid_point(pts[i]) || n.squaredNorm() < 0.5) continue;
    sample.emplace_back(vec(pts[i]).cast<double>(), n.normalized());
    spread += sample.back().second * sample.back().second.transpose();
  }
  if (sample.size() < 10) return std::nullopt;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(spread);  // eigenvalues ascending
  const Eigen::Vector3d lambda = eig.eigenvalues();
  if (!(lambda(2) > 0) || lambda(0) > kAcrossAxis * lambda(2) || lambda(1) < kTurning * lambda(2)) return std::nullopt;
  Cylinder c;
  c.axis = eig.eigenvectors().col(0);
  const Eigen::Matrix3d across_axis = Eigen::Matrix3d::Identity() - c.axis * c.axis.transpose();
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& [p, n] : sample) {
    const Eigen::Vector3d m = (across_axis * n).normalized();
    const Eigen::Matrix3d off_line = across_axis - m * m.transpose();  // in the plane across the axis, off the line
    a += off_line;
    b += off_line * p;
  }
  a += c.axis * c.axis.transpose();  // the centre's position along the axis: pinned at 0 (b has no part there)
  c.point = a.ldlt().solve(b);
  for (const auto& [p, n] : sample) {
    const Eigen::Vector3d d = p - c.point;
    c.radius += (d - d.dot(c.axis) * c.axis).norm();
  }
  c.radius /= static_cast<double>(sample.size());
  if (!std::isfinite(c.radius) || c.radius > kMaxRadius) return std::nullopt;
  return c;
}

std::vector<CurvatureLink> curvature_links(const std::vector<Patch>& patches, const std::vector<PatchPair>& linked,
                                           const cv::Mat& assigned_labels, const cv::Mat& points,
                                           const NormalPlanes& normals, const Camera& camera, const Params& params) {
  std::vector<CurvatureLink> out;
  const auto& p = params.curvature;
  if (!p.enabled || (!p.open_objects && !p.occluded)) return out;
  const bool planes_ok = std::all_of(normals.begin(), normals.end(), [&](const cv::Mat& plane) {
    return plane.type() == CV_32F && plane.size() == points.size() && plane.isContinuous();
  });
  if (assigned_labels.type() != CV_32S || points.type() != CV_32FC3 || assigned_labels.size() != points.size() ||
      !planes_ok)
    throw Error("curvature_links: labels (CV_32S), points (CV_32FC3) and normal planes (CV_32F) must be images of one size");
  std::vector<PatchPair> known = linked;
  for (auto& pair : known)
    if (pair.first > pair.second) std::swap(pair.first, pair.second);
  std::sort(known.begin(), known.end());

  std::vector<int> curved;
  for (size_t i = 0; i < patches.size(); ++i)
    if (patches[i].curved && !patches[i].pixels.empty()) curved.push_back(static_cast<int>(i));

  // Similar histograms first (121 bins per pair); the pixel work only for the similar pairs and, for the
  // concentric-walls rule, the others. Every pair is a candidate for the split-inside rule.
  std::vector<PatchPair> similar, walls, insides;
  for (size_t x = 0; x < curved.size(); ++x)
    for (size_t y = x + 1; y < curved.size(); ++y) {
      const int i = curved[x], j = curved[y];
      if (std::binary_search(known.begin(), known.end(), PatchPair(i, j))) continue;
      const auto& a = patches[static_cast<size_t>(i)];
      const auto& b = patches[static_cast<size_t>(j)];
      if (a.histogram.size() != b.histogram.size() || a.histogram.empty()) continue;
      if (p.open_objects && p.split_inside > 0) insides.emplace_back(i, j);
      if (histogram_similarity(a.histogram, b.histogram) > p.theta_h) similar.emplace_back(i, j);
      else if (p.open_objects && p.concentric > 0) walls.emplace_back(i, j);
    }
  if (similar.empty() && walls.empty() && insides.empty()) return out;

  const PixelScale px(camera.fx, camera.fy);
  const int gap = px.length(p.neighbour_gap_px);
  // Edge pixels join a patch only within the adjacency radius of its core pixels (paper d), so the
  // core box grown by that radius holds all of the patch's assigned pixels.
  const int assign_radius = px.length(params.adjacency.radius_px);
  auto box_of = [&](const Patch& patch) { return grown(patch.bbox, assign_radius); };
  PatchShapes shapes(patches, points, normals);
  const auto convexity_of = [&](int i) { return shapes.convexity_of(i); };
  const auto centre_of = [&](int i) -> const CurvatureCentre& { return shapes.centre_of(i); };
  // An open object's walls whose histograms differ (a bowl's outer wall faces down and out, the inside
  // seen over the rim up and in): opposite convexity, and concentric (beyond the paper). Decided here, so
  // that the boundary pass below covers only the pairs left. Boxes first: most pairs lie apart in the
  // image, and their convexity is not needed.
  const auto apart = [&](int i, int j) {
    return (grown(box_of(patches[static_cast<size_t>(i)]), gap) & box_of(patches[static_cast<size_t>(j)])).area() == 0;
  };
  std::erase_if(walls, [&](const PatchPair& pair) {
    const auto [i, j] = pair;
    if (apart(i, j) || convexity_of(i) * convexity_of(j) != -1) return true;
    const bool i_outer = convexity_of(i) > 0;
    return !concentric(centre_of(i_outer ? i : j), centre_of(i_outer ? j : i), p.concentric);
  });
  // Boundaries of all these patches in one pass over the image, the first time a pair needs them.
  std::vector<std::vector<cv::Point>> boundary_by_id;
  auto boundary_of = [&](int i) -> const std::vector<cv::Point>& {
    if (boundary_by_id.empty()) {
      std::vector<char> wanted;
      int y_begin = assigned_labels.rows, y_end = 0;  // the rows of their boxes: only these hold their pixels
      for (const auto* pairs : {&similar, &walls})
        for (const auto& [x, y] : *pairs)
          for (const int k : {x, y}) {
            const Patch& patch = patches[static_cast<size_t>(k)];
            const int id = patch.id;
            if (id > static_cast<int>(wanted.size())) wanted.resize(static_cast<size_t>(id), 0);
            if (id <= 0) continue;
            wanted[static_cast<size_t>(id - 1)] = 1;
            const cv::Rect box = box_of(patch);
            y_begin = std::min(y_begin, box.y);
            y_end = std::max(y_end, box.y + box.height);
          }
      boundary_by_id = boundaries(assigned_labels, wanted, y_begin, y_end);
    }
    return boundary_by_id[static_cast<size_t>(patches[static_cast<size_t>(i)].id - 1)];
  };
  auto neighbours = [&](int i, int j) {
    const auto& a = patches[static_cast<size_t>(i)];
    const auto& b = patches[static_cast<size_t>(j)];
    if (a.id <= 0 || b.id <= 0 || apart(i, j)) return false;
    return within_gap(boundary_of(i), boundary_of(j), gap, assigned_labels.size());
  };
  std::vector<std::unique_ptr<BinnedPixels>> binned(patches.size());
  auto binned_of = [&](int i) -> const BinnedPixels& {
    auto& b = binned[static_cast<size_t>(i)];
    const Patch& patch = patches[static_cast<size_t>(i)];
    if (!b) b = std::make_unique<BinnedPixels>(patch, histogram_side(patch.histogram), points, normals);
    return *b;
  };
  // Cheapest test first per rule; the image-neighbour test (which decides between the two rules)
  // only for pairs that one rule would link.
  for (const auto& [i, j] : similar) {
    const auto& a = patches[static_cast<size_t>(i)];
    const auto& b = patches[static_cast<size_t>(j)];
    // Open object: the outer (convex) and inner (concave) wall of a cup or bowl meet at the rim, and share
    // their centre of curvature (beyond the paper: two cans side by side, one read as concave, do not).
    if (p.open_objects && convexity_of(i) * convexity_of(j) == -1) {
      const bool i_outer = convexity_of(i) > 0;
      if (neighbours(i, j) &&
          (p.open_centre <= 0 || concentric(centre_of(i_outer ? i : j), centre_of(i_outer ? j : i), p.open_centre))) {
        out.push_back({{i, j}, Cue::CurvatureOpen});
        continue;
      }
    }
    // Occluded curved object: aligned, with an occluder between, and not image neighbours.
    if (p.occluded && aligned_and_occluded(a, binned_of(i), b, binned_of(j), points, camera, params) && !neighbours(i, j))
      out.push_back({{i, j}, Cue::CurvatureOccluded});
  }
  for (const auto& [i, j] : walls)
    if (neighbours(i, j)) out.push_back({{i, j}, Cue::CurvatureOpen});
  // The inside of one open object that something standing in it or in front of it splits (a can in a bowl):
  // two concave patches on one sphere or cylinder (beyond the paper). Their histograms differ (the two
  // halves face each other), and they need not be image neighbours.
  for (const PatchPair& pair : insides) {
    const auto [i, j] = pair;
    if (convexity_of(i) != -1 || convexity_of(j) != -1 || !one_surface(centre_of(i), centre_of(j), p.split_inside)) continue;
    if (std::none_of(out.begin(), out.end(), [&](const CurvatureLink& l) { return l.pair == pair; }))
      out.push_back({pair, Cue::CurvatureOccluded});
  }
  return out;
}

std::vector<PatchPair> creases_inside(const std::vector<Patch>& patches, const std::vector<PatchPair>& pairs,
                                      const cv::Mat& points, const NormalPlanes& normals, double share) {
  std::vector<PatchPair> out;
  if (share <= 0) return out;
  PatchShapes shapes(patches, points, normals);  // a patch meets several others
  const auto concave = [&](int i) { return shapes.convexity_of(i) == -1; };
  const auto centre_of = [&](int i) -> const CurvatureCentre& { return shapes.centre_of(i); };
  // The centres first: on most creases (a box on a box, a can on a book) one side has none. Creases with the
  // table are no link of the graph.
  const auto candidate = [&](int i) { return patches[static_cast<size_t>(i)].curved && !patches[static_cast<size_t>(i)].table; };
  for (const PatchPair& pair : pairs) {
    if (!candidate(pair.first) || !candidate(pair.second)) continue;
    if (one_surface(centre_of(pair.first), centre_of(pair.second), share) && concave(pair.first) && concave(pair.second))
      out.push_back(pair);
  }
  return out;
}

}  // namespace clutterseg
