#include "clutterseg/curvature.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "clutterseg/occlusion.hpp"

namespace clutterseg {

namespace {

// |correlation| between normal and position along the direction the normals turn in, above which
// the sign decides convexity. An ideal cylinder or sphere gives exactly +-1; noise and a flat part
// pull it towards 0.
constexpr double kConvexityCorrelation = 0.5;
constexpr int kMinPeakPoints = 3;  // fewest peak-bin points per patch for a line fit

Eigen::Vector3f vec(const cv::Vec3f& v) { return {v[0], v[1], v[2]}; }

// The bin of normal_histogram() (patches.cpp) that a normal falls into.
int histogram_bin(const cv::Vec3f& n, int bins) {
  auto bin = [bins](float c) { return std::clamp(static_cast<int>((c + 1.f) * 0.5f * bins), 0, bins - 1); };
  return bin(n[1]) * bins + bin(n[0]);
}

int histogram_side(const std::vector<float>& histogram) {
  return static_cast<int>(std::lround(std::sqrt(static_cast<double>(histogram.size()))));
}

// Image bounding box of each patch in the label image (edge pixels included once assigned).
std::vector<cv::Rect> label_boxes(const cv::Mat& labels, int num_patches) {
  std::vector<cv::Rect> boxes(static_cast<size_t>(num_patches));
  std::vector<int> x0(boxes.size(), labels.cols), y0(boxes.size(), labels.rows), x1(boxes.size(), -1), y1(boxes.size(), -1);
  for (int y = 0; y < labels.rows; ++y) {
    const int* row = labels.ptr<int>(y);
    for (int x = 0; x < labels.cols; ++x) {
      const int id = row[x];
      if (id <= 0 || id > num_patches) continue;
      const auto k = static_cast<size_t>(id - 1);
      x0[k] = std::min(x0[k], x); x1[k] = std::max(x1[k], x);
      y0[k] = std::min(y0[k], y); y1[k] = std::max(y1[k], y);
    }
  }
  for (size_t k = 0; k < boxes.size(); ++k)
    if (x1[k] >= 0) boxes[k] = cv::Rect(x0[k], y0[k], x1[k] - x0[k] + 1, y1[k] - y0[k] + 1);
  return boxes;
}

cv::Rect grown(const cv::Rect& r, int by) { return {r.x - by, r.y - by, r.width + 2 * by, r.height + 2 * by}; }

// Some pixel of patch a lies within `gap` pixels of some pixel of patch b. Both such pixels lie in
// the overlap of the two grown boxes, so a distance transform over that overlap decides it exactly.
bool image_neighbours(const cv::Mat& labels, int id_a, const cv::Rect& box_a, int id_b, const cv::Rect& box_b, int gap) {
  if (box_a.empty() || box_b.empty()) return false;
  const cv::Rect roi = grown(box_a, gap) & grown(box_b, gap) & cv::Rect(0, 0, labels.cols, labels.rows);
  if (roi.empty()) return false;
  const cv::Mat window = labels(roi);
  const cv::Mat not_a = window != id_a;
  if (cv::countNonZero(not_a) == static_cast<int>(window.total())) return false;
  cv::Mat distance;
  cv::distanceTransform(not_a, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  for (int y = 0; y < roi.height; ++y) {
    const int* l = window.ptr<int>(y);
    const float* d = distance.ptr<float>(y);
    for (int x = 0; x < roi.width; ++x)
      if (l[x] == id_b && d[x] <= static_cast<float>(gap)) return true;
  }
  return false;
}

// Points of a patch whose normal falls into histogram bin `bin`.
std::vector<Eigen::Vector3f> bin_points(const Patch& patch, int bin, int bins, const cv::Mat& points, const cv::Mat& normals) {
  std::vector<Eigen::Vector3f> out;
  const auto* pts = points.ptr<cv::Vec3f>();
  const auto* nrm = normals.ptr<cv::Vec3f>();
  for (int i : patch.pixels)
    if (pts[i][2] > 0 && histogram_bin(nrm[i], bins) == bin) out.push_back(vec(pts[i]));
  return out;
}

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
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto* set : {&a, &b})
    for (const auto& p : *set) {
      const Eigen::Vector3d d = p.cast<double>() - mean;
      cov += d * d.transpose();
    }
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
bool aligned_and_occluded(const Patch& a, const Patch& b, const cv::Mat& points, const cv::Mat& normals,
                          const Camera& camera, const Params& params) {
  const int bins = histogram_side(a.histogram);
  int peak = 0;
  float best = -1;
  for (size_t k = 0; k < a.histogram.size(); ++k) {
    const float shared = std::min(a.histogram[k], b.histogram[k]);
    if (shared > best) { best = shared; peak = static_cast<int>(k); }
  }
  const auto pa = bin_points(a, peak, bins, points, normals), pb = bin_points(b, peak, bins, points, normals);
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

}  // namespace

double histogram_similarity(const std::vector<float>& a, const std::vector<float>& b) {
  if (a.size() != b.size()) throw Error("histogram_similarity: histograms differ in size");
  double s = 0;
  for (size_t k = 0; k < a.size(); ++k) s += std::min(a[k], b[k]);
  return s;
}

int convexity(const Patch& patch, const cv::Mat& points, const cv::Mat& normals, int bins) {
  // Physically: on a convex surface the (outward, camera-facing) normal turns the way one walks,
  // dn = S dp with a positive shape operator S; on a concave one it turns against. We find the
  // direction e in which the normals vary most (the major axis of the histogram blob, paper Eq. 4)
  // and correlate n.e with p.e over the patch: the sign is the sign of the curvature along e.
  const auto* pts = points.ptr<cv::Vec3f>();
  const auto* nrm = normals.ptr<cv::Vec3f>();
  std::vector<int> valid;
  valid.reserve(patch.pixels.size());
  for (int i : patch.pixels)
    if (pts[i][2] > 0 && (nrm[i][0] != 0 || nrm[i][1] != 0 || nrm[i][2] != 0)) valid.push_back(i);
  if (valid.size() < 10) return 0;

  Eigen::Vector3d n_mean = Eigen::Vector3d::Zero(), p_mean = Eigen::Vector3d::Zero();
  for (int i : valid) { n_mean += vec(nrm[i]).cast<double>(); p_mean += vec(pts[i]).cast<double>(); }
  n_mean /= static_cast<double>(valid.size());
  p_mean /= static_cast<double>(valid.size());
  Eigen::Matrix3d n_cov = Eigen::Matrix3d::Zero();
  for (int i : valid) {
    const Eigen::Vector3d d = vec(nrm[i]).cast<double>() - n_mean;
    n_cov += d * d.transpose();
  }
  n_cov /= static_cast<double>(valid.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(n_cov);
  const Eigen::Vector3d e = eig.eigenvectors().col(2);
  // Normals that vary by less than a histogram bin along e: no curvature to judge.
  if (2 * std::sqrt(std::max(0.0, eig.eigenvalues()(2))) < 2.0 / std::max(1, bins)) return 0;

  double snp = 0, snn = 0, spp = 0;
  for (int i : valid) {
    const double dn = (vec(nrm[i]).cast<double>() - n_mean).dot(e);
    const double dp = (vec(pts[i]).cast<double>() - p_mean).dot(e);
    snp += dn * dp; snn += dn * dn; spp += dp * dp;
  }
  if (snn <= 0 || spp <= 0) return 0;
  const double correlation = snp / std::sqrt(snn * spp);
  return correlation > kConvexityCorrelation ? 1 : correlation < -kConvexityCorrelation ? -1 : 0;
}

std::vector<CurvatureLink> curvature_links(const std::vector<Patch>& patches, const std::vector<PatchPair>& linked,
                                           const cv::Mat& assigned_labels, const cv::Mat& points,
                                           const cv::Mat& normals, const Camera& camera, const Params& params) {
  std::vector<CurvatureLink> out;
  const auto& p = params.curvature;
  if (!p.enabled || (!p.open_objects && !p.occluded)) return out;
  std::vector<PatchPair> known = linked;
  for (auto& pair : known)
    if (pair.first > pair.second) std::swap(pair.first, pair.second);
  std::sort(known.begin(), known.end());

  std::vector<int> curved;
  for (size_t i = 0; i < patches.size(); ++i)
    if (patches[i].curved && !patches[i].pixels.empty()) curved.push_back(static_cast<int>(i));

  // Similar histograms first (121 bins per pair); the pixel work only for the similar pairs.
  std::vector<PatchPair> similar;
  for (size_t x = 0; x < curved.size(); ++x)
    for (size_t y = x + 1; y < curved.size(); ++y) {
      const int i = curved[x], j = curved[y];
      if (std::binary_search(known.begin(), known.end(), PatchPair(i, j))) continue;
      const auto& a = patches[static_cast<size_t>(i)];
      const auto& b = patches[static_cast<size_t>(j)];
      if (a.histogram.size() != b.histogram.size() || a.histogram.empty()) continue;
      if (histogram_similarity(a.histogram, b.histogram) > p.theta_h) similar.emplace_back(i, j);
    }
  if (similar.empty()) return out;

  const int gap = std::max(1, static_cast<int>(std::lround(p.neighbour_gap_px * resolution_scale(assigned_labels.cols))));
  int max_id = 0;
  for (const auto& patch : patches) max_id = std::max(max_id, patch.id);
  const auto boxes = label_boxes(assigned_labels, max_id);
  auto box_of = [&](const Patch& patch) { return patch.id > 0 ? boxes[static_cast<size_t>(patch.id - 1)] : cv::Rect(); };
  std::vector<int> convex(patches.size(), 2);  // 2 = not computed yet
  auto convexity_of = [&](int i) {
    auto& c = convex[static_cast<size_t>(i)];
    if (c == 2) c = convexity(patches[static_cast<size_t>(i)], points, normals, histogram_side(patches[static_cast<size_t>(i)].histogram));
    return c;
  };
  for (const auto& [i, j] : similar) {
    const auto& a = patches[static_cast<size_t>(i)];
    const auto& b = patches[static_cast<size_t>(j)];
    if (image_neighbours(assigned_labels, a.id, box_of(a), b.id, box_of(b), gap)) {
      // Open object: the outer (convex) and inner (concave) wall of a cup or bowl meet at the rim.
      if (p.open_objects && convexity_of(i) * convexity_of(j) == -1) out.push_back({{i, j}, Cue::CurvatureOpen});
    } else if (p.occluded && aligned_and_occluded(a, b, points, normals, camera, params)) {
      out.push_back({{i, j}, Cue::CurvatureOccluded});
    }
  }
  return out;
}

}  // namespace clutterseg
