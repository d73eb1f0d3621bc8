// The support plane (table), decided per patch. See include/clutterseg/support.hpp and docs/OBJECTS.md.
#include "clutterseg/support.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <span>
#include <opencv2/imgproc.hpp>

#include "clutterseg/parallel.hpp"
#include "clutterseg/patches.hpp"

namespace clutterseg {

namespace {

Eigen::Vector3f point_at(const cv::Vec3f* pts, int i) { return {pts[i][0], pts[i][1], pts[i][2]}; }

// Params::Support::glued_share is on: a table with objects glued to it is found and cut (beyond the paper).
bool glued(const Params::Support& params) { return params.glued_share > 0; }

// The share of a table patch's points that must lie within the plane's tolerance for the refit to keep it and
// for cut_off_table to cut it: half, or glued_share when that is on and lower.
double table_share(const Params::Support& params) { return glued(params) ? std::min(0.5, params.glued_share) : 0.5; }

// Largest a * x + b * y over the points, a and b in {-1, 0, 1} (exact: no rounding but the one sum).
CLUTTERSEG_ROW_KERNEL float largest_projection(const float* __restrict x, const float* __restrict y, int n, float a,
                                               float b) {
  float largest = -std::numeric_limits<float>::infinity();
#pragma omp simd reduction(max : largest)
  for (int i = 0; i < n; ++i) largest = std::max(largest, a * x[i] + b * y[i]);
  return largest;
}

// Points with a * x + b * y >= value.
CLUTTERSEG_ROW_KERNEL int count_at_least(const float* __restrict x, const float* __restrict y, int n, float a, float b,
                                         float value) {
  int count = 0;
  for (int i = 0; i < n; ++i) count += a * x[i] + b * y[i] >= value;
  return count;
}

// Index of the first point with a * x + b * y >= value (n if none): blocks are counted in a vectorised
// pass, and only the block that holds it is scanned point by point.
int first_at_least(const float* x, const float* y, int n, float a, float b, float value) {
  constexpr int kBlock = 64;
  for (int begin = 0; begin < n; begin += kBlock) {
    const int end = std::min(n, begin + kBlock);
    if (count_at_least(x + begin, y + begin, end - begin, a, b, value) == 0) continue;
    for (int i = begin; i < end; ++i)
      if (a * x[i] + b * y[i] >= value) return i;
  }
  return n;
}

// keep[i] &= (a * x + b * y > offset) for one edge of the inner polygon.
CLUTTERSEG_ROW_KERNEL void keep_inside(const float* __restrict x, const float* __restrict y, int n, float a, float b,
                                       float offset, uchar* __restrict keep) {
  for (int i = 0; i < n; ++i) keep[i] &= static_cast<uchar>(a * x[i] + b * y[i] > offset);
}

// cv::convexHull of plane points. It sorts every point (~0.4 ms for the 4000 of a table); points more
// than 1 mm inside the polygon of the extreme points in 8 directions cannot be hull vertices, so
// dropping them first gives the same hull.
std::vector<cv::Point2f> convex_hull(const std::vector<cv::Point2f>& points) {
  const int n = static_cast<int>(points.size());
  std::vector<float> xs(points.size()), ys(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    xs[i] = points[i].x;
    ys[i] = points[i].y;
  }
  // Extreme points along x, y, x + y and x - y, in counter-clockwise order of direction: the first
  // point reaching the largest projection.
  constexpr float kDx[8] = {1, 1, 0, -1, -1, -1, 0, 1}, kDy[8] = {0, 1, 1, 1, 0, -1, -1, -1};
  std::array<cv::Point2f, 8> extreme;
  for (int k = 0; k < 8; ++k) {
    const float largest = largest_projection(xs.data(), ys.data(), n, kDx[k], kDy[k]);
    const int first = first_at_least(xs.data(), ys.data(), n, kDx[k], kDy[k], largest);
    extreme[static_cast<size_t>(k)] = points[static_cast<size_t>(first < n ? first : 0)];
  }
  std::vector<cv::Point2f> polygon;
  for (const cv::Point2f& e : extreme)
    if (polygon.empty() || e != polygon.back()) polygon.push_back(e);
  if (polygon.size() > 1 && polygon.front() == polygon.back()) polygon.pop_back();
  // Points more than kMargin inside every edge of that polygon (edges as lines n . p = offset, unit
  // normal n pointing inwards) cannot be hull vertices.
  constexpr float kMargin = 0.001f;  // [m], far above the float rounding of plane coordinates
  std::vector<uchar> inside(points.size(), polygon.size() >= 3 ? 1 : 0);
  for (size_t k = 0; polygon.size() >= 3 && k < polygon.size(); ++k) {
    const cv::Point2f edge = polygon[(k + 1) % polygon.size()] - polygon[k];
    const cv::Point2f normal = cv::Point2f(-edge.y, edge.x) / std::hypot(edge.x, edge.y);
    keep_inside(xs.data(), ys.data(), n, normal.x, normal.y, normal.dot(polygon[k]) + kMargin, inside.data());
  }
  std::vector<cv::Point2f> outer;
  for (size_t i = 0; i < points.size(); ++i)
    if (!inside[i]) outer.push_back(points[i]);
  std::vector<cv::Point2f> hull;
  cv::convexHull(outer, hull);
  return hull;
}

// Dilation of `cells` (0 or 255) by `kernel` (each kernel row a single span of ones, as in an elliptic kernel);
// the same cells as cv::dilate, which costs ~1 ms on a table-sized region, by painting for every run of
// set cells the span each kernel row spreads it to (a filled convex polygon has one run per row).
cv::Mat dilate_by_spans(const cv::Mat& cells, const cv::Mat& kernel) {
  const cv::Point anchor(kernel.cols / 2, kernel.rows / 2);  // cv::dilate's default anchor
  std::vector<std::pair<int, int>> span;  // first and last column of ones in each kernel row
  for (int j = 0; j < kernel.rows; ++j) {
    const uchar* k = kernel.ptr<uchar>(j);
    int first = 0, last = kernel.cols - 1;
    while (first < kernel.cols && !k[first]) ++first;
    while (last >= first && !k[last]) --last;
    span.emplace_back(first, last);
  }
  cv::Mat out(cells.size(), CV_8U, cv::Scalar(0));
  const auto cols = static_cast<size_t>(cells.cols);
  for (int y = 0; y < cells.rows; ++y) {
    const uchar* row = cells.ptr<uchar>(y);
    // Runs found by memchr (SIMD): a row is mostly empty or one run.
    for (int left = 0; left < cells.cols; ++left) {
      const void* set = std::memchr(row + left, 255, cols - static_cast<size_t>(left));
      if (!set) break;
      left = static_cast<int>(static_cast<const uchar*>(set) - row);
      const void* unset = std::memchr(row + left, 0, cols - static_cast<size_t>(left));
      const int right = unset ? static_cast<int>(static_cast<const uchar*>(unset) - row) - 1 : cells.cols - 1;
      // dst(x, y) = max over kernel cells (i, j) of src(x + i - anchor.x, y + j - anchor.y).
      for (int j = 0; j < kernel.rows; ++j) {
        const auto [first, last] = span[static_cast<size_t>(j)];
        const int to_y = y - j + anchor.y;
        if (last < first || to_y < 0 || to_y >= out.rows) continue;
        const int x0 = std::max(0, left - last + anchor.x), x1 = std::min(out.cols - 1, right - first + anchor.x);
        if (x0 <= x1) std::memset(out.ptr<uchar>(to_y) + x0, 255, static_cast<size_t>(x1 - x0 + 1));
      }
      left = right;
    }
  }
  return out;
}

// Points within their tolerance of the plane (a, b, c, d): Plane::distance's arithmetic in its order
// (Eigen's dot is a*x + (b*y + c*z)), so the count is the one it gives, lane by lane.
CLUTTERSEG_ROW_KERNEL int count_within(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                                       const float* __restrict tolerance, int n, float a, float b, float c, float d) {
  int count = 0;
  for (int k = 0; k < n; ++k) count += std::abs(a * x[k] + (b * y[k] + c * z[k]) + d) <= tolerance[k];
  return count;
}

// Every stride-th valid pixel of `lists` taken as one list (not copied into one: a copy of every table
// pixel was most of support_of), at most about `most` of them (bounded work per patch).
std::vector<int> sample_of(std::span<const std::vector<int>* const> lists, const cv::Vec3f* pts, size_t most) {
  size_t total = 0;
  for (const std::vector<int>* pixels : lists) total += pixels->size();
  const size_t stride = std::max<size_t>(1, total / most);
  std::vector<int> sample;
  sample.reserve(total / stride + 1);
  size_t k = 0;  // the next index to visit, counted from the start of the current list
  for (const std::vector<int>* pixels : lists) {
    for (; k < pixels->size(); k += stride)
      if (valid_point(pts[(*pixels)[k]])) sample.push_back((*pixels)[k]);
    k -= pixels->size();
  }
  return sample;
}

std::vector<int> sample_of(const std::vector<int>& pixels, const cv::Vec3f* pts, size_t most) {
  const std::vector<int>* one[] = {&pixels};
  return sample_of(one, pts, most);
}

// Dominant plane of a patch: RANSAC over a sample of its points (a table patch may hold the foot of an
// object that the edges did not separate), refined by least squares on the inliers. The band grows with
// the patch's depth (plane_tolerance). Deterministic: the draws are seeded by the patch size. Returns the
// inlier share.
double dominant_plane(const std::vector<int>& pixels, const cv::Mat& points, double band, Plane& plane) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const std::vector<int> sample = sample_of(pixels, pts, sample_budget(1000, points));
  if (sample.size() < 10) return 0;
  std::vector<float> tolerance(sample.size());
  for (size_t k = 0; k < sample.size(); ++k) tolerance[k] = plane_tolerance(band, pts[sample[k]][2]);
  std::uint64_t state = 0x9e3779b97f4a7c15ULL ^ pixels.size();
  auto next = [&] {  // xorshift64: a small, portable, seeded generator
    state ^= state << 13; state ^= state >> 7; state ^= state << 17;
    return static_cast<size_t>(state % sample.size());
  };
  // The sample's coordinates as planes: the 30 counts below read them contiguously (and vectorise).
  std::vector<float> sx(sample.size()), sy(sample.size()), sz(sample.size());
  for (size_t k = 0; k < sample.size(); ++k) {
    sx[k] = pts[sample[k]][0];
    sy[k] = pts[sample[k]][1];
    sz[k] = pts[sample[k]][2];
  }
  auto inliers_of = [&](const Plane& candidate) {
    return count_within(sx.data(), sy.data(), sz.data(), tolerance.data(), static_cast<int>(sample.size()),
                        candidate.normal.x(), candidate.normal.y(), candidate.normal.z(), candidate.offset);
  };
  int best_count = -1;
  Plane best;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Eigen::Vector3f a = point_at(pts, sample[next()]), b = point_at(pts, sample[next()]),
                          c = point_at(pts, sample[next()]);
    Eigen::Vector3f n = (b - a).cross(c - a);
    if (n.norm() < 1e-9f) continue;
    n.normalize();
    if (n.dot(a) > 0) n = -n;
    const Plane candidate{n, -n.dot(a)};
    const int count = inliers_of(candidate);
    if (count > best_count) { best_count = count; best = candidate; }
  }
  if (best_count <= 0) return 0;
  std::vector<int> inliers;
  for (size_t k = 0; k < sample.size(); ++k)
    if (std::abs(best.distance(point_at(pts, sample[k]))) <= tolerance[k]) inliers.push_back(sample[k]);
  plane = best;
  Plane refined;
  if (fit_plane(inliers, points, refined)) {
    const int count = inliers_of(refined);
    if (count >= best_count) {
      plane = refined;
      return static_cast<double>(count) / static_cast<double>(sample.size());
    }
  }
  return static_cast<double>(best_count) / static_cast<double>(sample.size());
}

// Least-squares plane of the points within plane_tolerance of `plane` among `pixels` of every patch in
// `table` (a sample per patch): the table seen as one plane. The sample is not scaled down in small frames
// (sample_budget): the final plane decides table membership everywhere, and fewer points tilt it (ycbv-0000
// at 320x240: fp 4.3 -> 5.1 with a quarter of the sample); once per frame, it costs little.
bool refit(const std::vector<Patch>& patches, const std::vector<int>& table, const cv::Mat& points, double band,
           Plane& plane) {
  const auto* pts = points.ptr<cv::Vec3f>();
  PlaneFit fit;
  for (int p : table)
    for (int i : sample_of(patches[static_cast<size_t>(p)].pixels, pts, 3000)) {
      const Eigen::Vector3f q = point_at(pts, i);
      if (std::abs(plane.distance(q)) <= plane_tolerance(band, q.z())) fit.add(q);
    }
  return fit.plane(plane);
}

// A patch a plane's refit is made from: normal close to the plane's, `share` of the points (half unless
// told) within the tolerance (a patch that holds an object's foot still counts).
bool is_near(const Patch& patch, const cv::Mat& points, const Plane& plane, const Params::Support& params,
             double share = 0.5) {
  const float min_cos = static_cast<float>(std::cos(params.table_angle_deg * M_PI / 180.0));
  return patch.mean_normal.dot(plane.normal) >= min_cos && mostly_within(patch.pixels, points, plane, params.plane_band, share);
}

// The patches that are is_near the plane.
std::vector<int> patches_near(const std::vector<Patch>& patches, const cv::Mat& points, const Plane& plane,
                              const Params::Support& params, double share = 0.5) {
  std::vector<int> near;
  for (size_t p = 0; p < patches.size(); ++p)
    if (is_near(patches[p], points, plane, params, share)) near.push_back(static_cast<int>(p));
  return near;
}

}  // namespace

bool PlaneFit::plane(Plane& plane) const {
  if (n < 10) return false;
  const Eigen::Vector3d mean = sum / static_cast<double>(n);
  Eigen::Matrix3d outer;
  outer << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(outer / static_cast<double>(n) - mean * mean.transpose());
  if (eig.eigenvalues()(1) < 1e-8) return false;  // a line of points (spread below 0.1 mm across)
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(mean) > 0) normal = -normal;  // facing the camera
  plane.normal = normal.cast<float>();
  plane.offset = static_cast<float>(-normal.dot(mean));
  return true;
}

bool fit_plane(const std::vector<int>& pixels, const cv::Mat& points, Plane& plane) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t stride = std::max<size_t>(1, pixels.size() / sample_budget(3000, points));
  PlaneFit fit;
  for (size_t k = 0; k < pixels.size(); k += stride)
    if (valid_point(pts[pixels[k]])) fit.add(point_at(pts, pixels[k]));
  return fit.plane(plane);
}

bool mostly_within(const std::vector<int>& pixels, const cv::Mat& points, const Plane& plane, double band,
                   double share) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t stride = std::max<size_t>(1, pixels.size() / sample_budget(2000, points));
  const size_t visits = (pixels.size() + stride - 1) / stride;
  int in = 0, n = 0;
  // Checked every kBlock visits: once the best final share (in + left) / (n + left) is below `share` it
  // stays below (each visit lowers in + left - share * (n + left) or keeps it), so a later check gives
  // the same answer with a cheaper loop. Half a point of margin keeps rounding out of it.
  constexpr size_t kBlock = 16;
  for (size_t block = 0; block < visits; block += kBlock) {
    const size_t block_end = std::min(visits, block + kBlock);
    for (size_t v = block; v < block_end; ++v) {
      const int i = pixels[v * stride];
      if (!valid_point(pts[i])) continue;
      ++n;
      in += std::abs(plane.distance(point_at(pts, i))) <= plane_tolerance(band, pts[i][2]);
    }
    const double left = static_cast<double>(visits - block_end);
    if (in + left < share * (n + left) - 0.5) return false;
  }
  return n && static_cast<double>(in) / n >= share;
}

namespace {

// Points a region is made from, at most about (the hull of a sample is the region's outline to within
// the sample's spacing, a few millimetres).
constexpr size_t kRegionSample = 4000;

// The region of `sample` (valid pixels) in `plane`, grown by `margin` [m].
PlaneRegion region_of_sample(const Plane& plane, const std::vector<int>& sample, const cv::Mat& points, double margin) {
  PlaneRegion r;
  r.plane = plane;
  r.u = plane.normal.unitOrthogonal();
  r.v = plane.normal.cross(r.u);
  const auto* pts = points.ptr<cv::Vec3f>();
  std::vector<cv::Point2f> projected;
  projected.reserve(sample.size());
  for (int i : sample) {
    const Eigen::Vector3f q = point_at(pts, i);
    projected.emplace_back(r.u.dot(q), r.v.dot(q));
  }
  if (projected.size() < 3) return r;
  const std::vector<cv::Point2f> hull = convex_hull(projected);
  cv::Rect2f box(hull[0], hull[0]);
  for (const auto& h : hull) {
    const float x1 = std::max(box.x + box.width, h.x), y1 = std::max(box.y + box.height, h.y);
    box.x = std::min(box.x, h.x);
    box.y = std::min(box.y, h.y);
    box.width = x1 - box.x;
    box.height = y1 - box.y;
  }
  const int pad = static_cast<int>(std::ceil(margin / PlaneRegion::kCell)) + 1;
  r.origin = {box.x - pad * PlaneRegion::kCell, box.y - pad * PlaneRegion::kCell};
  // Bounded: a region larger than 20 m x 20 m is cut (no depth sensor sees one).
  const int cols = std::min(2000, static_cast<int>(std::ceil(box.width / PlaneRegion::kCell)) + 2 * pad + 1);
  const int rows = std::min(2000, static_cast<int>(std::ceil(box.height / PlaneRegion::kCell)) + 2 * pad + 1);
  r.cells = cv::Mat(rows, cols, CV_8U, cv::Scalar(0));
  std::vector<cv::Point> poly;
  for (const auto& h : hull)
    poly.emplace_back(static_cast<int>(std::lround((h.x - r.origin.x) / PlaneRegion::kCell)),
                      static_cast<int>(std::lround((h.y - r.origin.y) / PlaneRegion::kCell)));
  cv::fillConvexPoly(r.cells, poly, cv::Scalar(255));
  if (pad > 1) r.cells = dilate_by_spans(r.cells, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * pad - 1, 2 * pad - 1}));
  return r;
}

}  // namespace

PlaneRegion region_of(const Plane& plane, const std::vector<int>& pixels, const cv::Mat& points, double margin) {
  return region_of_sample(plane, sample_of(pixels, points.ptr<cv::Vec3f>(), sample_budget(kRegionSample, points)), points, margin);
}

Eigen::Vector3f up_in_camera(const Camera& camera) {
  if (camera.camera_to_robot.isIdentity()) return -Eigen::Vector3f::UnitY();  // the image's up
  return (camera.camera_to_robot.topLeftCorner<3, 3>().transpose() * Eigen::Vector3d::UnitZ()).cast<float>();
}

std::optional<Plane> find_support_plane(const std::vector<Patch>& patches, const cv::Mat& points, const Camera& camera,
                                        const Params::Support& params) {
  if (points.type() != CV_32FC3) throw Error("find_support_plane: points must be CV_32FC3");
  const auto* pts = points.ptr<cv::Vec3f>();
  size_t patch_pixels = 0;
  for (const auto& p : patches) patch_pixels += p.pixels.size();
  // The 4 largest planar patches with >= 2 % of the patch pixels, judged largest first (ties: lower
  // index), so RANSAC runs only until 4 are found; those facing up are the candidates. Planar: 60 % of
  // the points on one plane, or glued_share of them (a table with objects glued to it, beyond the paper).
  std::vector<int> by_size;
  for (size_t p = 0; p < patches.size(); ++p)
    if (static_cast<double>(patches[p].pixels.size()) >= 0.02 * static_cast<double>(patch_pixels)) by_size.push_back(static_cast<int>(p));
  std::stable_sort(by_size.begin(), by_size.end(), [&](int a, int b) {
    return patches[static_cast<size_t>(a)].pixels.size() > patches[static_cast<size_t>(b)].pixels.size();
  });
  // Which way is up: with a pose (camera_to_robot), the robot's z axis, and a support is within 45 deg of
  // horizontal; without one, the image's up, and a support's normal does not point down the image (a
  // camera looking straight down sees the table's normal at 90 deg from the image's up).
  const Eigen::Vector3f up = up_in_camera(camera);
  const float min_up = camera.camera_to_robot.isIdentity() ? -0.1f : static_cast<float>(std::cos(M_PI / 4));
  const double min_share = glued(params) ? std::min(0.6, params.glued_share) : 0.6;
  std::vector<int> candidates, large_planes;  // the 4 largest planes; those facing up are candidates
  std::vector<Plane> planes;
  for (size_t k = 0; k < by_size.size() && large_planes.size() < 4; ++k) {
    Plane plane;
    if (dominant_plane(patches[static_cast<size_t>(by_size[k])].pixels, points, params.plane_band, plane) < min_share) continue;
    large_planes.push_back(by_size[k]);
    if (plane.normal.dot(up) < min_up) continue;  // a wall seen from above, a ceiling: nothing stands on them
    candidates.push_back(by_size[k]);
    planes.push_back(plane);
  }
  if (candidates.empty()) return std::nullopt;

  // Score: pixels of the other patches (a sample of each) standing on the candidate: above it by more than
  // the tolerance and at most max_height, over its visible region. Other large planes do not count, so a
  // wall does not score the table in front of it, nor the floor below it. Without the region test
  // (`region` null) the score is an upper bound: more points count, and the lowest point is lower; it
  // is only needed up to where it passes `enough`.
  std::vector<std::vector<int>> samples(patches.size());  // empty for the large planes
  auto score_of = [&](const Plane& plane, const PlaneRegion* region, double enough) {
    double score = 0;
    for (size_t p = 0; p < patches.size() && score <= enough; ++p) {
      if (samples[p].empty()) continue;
      // A patch rests on the plane when its lowest point over the region is within contact_distance (a
      // box in front of a wall floats 20 cm off it; a box's side faces reach down to the table it stands on).
      int standing = 0;
      float lowest = std::numeric_limits<float>::infinity();
      for (int i : samples[p]) {
        const Eigen::Vector3f q = point_at(pts, i);
        const float h = plane.distance(q);
        if (h <= -plane_tolerance(params.plane_band, q.z()) || h > params.max_height || (region && !region->over(q))) continue;
        lowest = std::min(lowest, h);
        standing += h > plane_tolerance(params.plane_band, q.z());
      }
      if (lowest > params.contact_distance) continue;
      score += static_cast<double>(standing) / static_cast<double>(samples[p].size()) * static_cast<double>(patches[p].pixels.size());
    }
    return score;
  };
  // The best score, ties to the lower index. The region (most of the cost) is built only for a candidate
  // whose bound can beat the best so far; the largest candidate comes first, and is mostly the table.
  // One candidate needs no score.
  int best = 0;
  if (candidates.size() > 1) {
    for (size_t p = 0; p < patches.size(); ++p)
      if (std::find(large_planes.begin(), large_planes.end(), static_cast<int>(p)) == large_planes.end())
        samples[p] = sample_of(patches[p].pixels, pts, sample_budget(500, points));
    constexpr double kAll = std::numeric_limits<double>::infinity();
    double best_score = -1;
    for (size_t k = 0; k < candidates.size(); ++k) {
      if (k > 0 && score_of(planes[k], nullptr, best_score) <= best_score) continue;
      const PlaneRegion region = region_of(planes[k], patches[static_cast<size_t>(candidates[k])].pixels, points, params.region_margin);
      const double score = score_of(planes[k], &region, kAll);
      if (score > best_score) { best_score = score; best = static_cast<int>(k); }
    }
  }
  // Refit over every patch lying in the plane, twice: the second pass sees the pieces the first one's
  // better plane brings within the tolerance. A refit that no longer holds the patch it started from is
  // not the table seen better but pulled away by far pieces (their tolerance grows with depth, and far
  // points tilt a least-squares plane most): the plane before it stays (tabletop-realsense 000008). A
  // table with objects glued to it holds less than half its points in the plane; its points within the
  // tolerance are part of every refit, and it must keep glued_share of them.
  const int seed_index = candidates[static_cast<size_t>(best)];
  const Patch& seed = patches[static_cast<size_t>(seed_index)];
  Plane plane = planes[static_cast<size_t>(best)];
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<int> near = patches_near(patches, points, plane, params);
    if (glued(params) && !std::binary_search(near.begin(), near.end(), seed_index))
      near.insert(std::lower_bound(near.begin(), near.end(), seed_index), seed_index);
    Plane refitted = plane;
    if (near.empty() || !refit(patches, near, points, params.plane_band, refitted) ||
        !is_near(seed, points, refitted, params, table_share(params)))
      break;
    plane = refitted;
  }
  return plane;
}

bool lies_in(const Patch& patch, const cv::Mat& points, const Plane& plane, const Params::Support& params) {
  const float min_cos = static_cast<float>(std::cos(params.table_angle_deg * M_PI / 180.0));
  return patch.mean_normal.dot(plane.normal) >= min_cos && mostly_within(patch.pixels, points, plane, 0.5 * params.plane_band, 0.8);
}

int unmark_curved_table(std::vector<Patch>& patches, const Params::Support& params) {
  if (params.curved_bins_ratio <= 0) return 0;
  const Patch* largest = nullptr;
  for (const Patch& patch : patches)
    if (patch.table && (!largest || patch.pixels.size() > largest->pixels.size())) largest = &patch;
  if (!largest) return 0;
  const double limit = params.curved_bins_ratio * largest->occupied_bins;
  int unmarked = 0;
  for (Patch& patch : patches)
    if (patch.table && patch.occupied_bins > limit) {
      patch.table = false;
      ++unmarked;
    }
  return unmarked;
}

namespace {

// The pixels of `pixels` (valid points) farther from `plane` than plane_tolerance(band, z), on either side.
std::vector<int> off_plane(const std::vector<int>& pixels, const cv::Vec3f* pts, const Plane& plane, double band) {
  const float a = plane.normal.x(), b = plane.normal.y(), c = plane.normal.z(), d = plane.offset;
  const float k = static_cast<float>(band);
  std::vector<int> off;
  for (int i : pixels) {
    const float x = pts[i][0], y = pts[i][1], z = pts[i][2];
    const float h = a * x + b * y + c * z + d, tolerance = k * std::max(1.f, z * z);
    if (valid_depth(z) && std::abs(h) > tolerance) off.push_back(i);
  }
  return off;
}

}  // namespace

namespace {

// off[i] = 255 where point i (interleaved xyz) is valid and higher above the plane than k * max(1, z^2)
// (or, with `below`, farther from it on either side); returns how many are.
CLUTTERSEG_ROW_KERNEL int mark_off_plane(const float* __restrict xyz, int n, float a, float b, float c, float d,
                                         float k, bool below, uchar* __restrict off) {
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const float x = xyz[3 * i], y = xyz[3 * i + 1], z = xyz[3 * i + 2];
    const float h = a * x + b * y + c * z + d, tolerance = k * std::max(1.f, z * z);
    const int is_off = int{valid_depth(z)} & (int{h > tolerance} | (int{below} & int{h < -tolerance}));
    off[i] = is_off ? 255 : 0;
    count += is_off;
  }
  return count;
}

// Calls visit(first, count) for each run of consecutive indices in `pixels` (increasing, as a patch's
// pixels are: its row segments). Strictly increasing indices 8 apart in value and in position have no
// gap between them, so a run is crossed eight at a time.
template <class Visit>
void for_each_pixel_run(const std::vector<int>& pixels, Visit visit) {
  const size_t n = pixels.size();
  for (size_t begin = 0; begin < n;) {
    size_t end = begin + 1;
    while (end + 8 <= n && pixels[end + 7] - pixels[end - 1] == 8) end += 8;
    while (end < n && pixels[end] == pixels[end - 1] + 1) ++end;
    visit(pixels[begin], static_cast<int>(end - begin));
    begin = end;
  }
}

}  // namespace

int cut_off_table(cv::Mat& edges, const std::vector<Patch>& patches, const cv::Mat& patch_labels, const cv::Mat& points,
                  const Plane& plane, const Params::Support& params, int min_px) {
  // Heights of the table patches' pixels only, run by run (vectorised), counted into a row-sized scratch
  // line; the mark image is made only for a patch to cut (most frames have none).
  const auto* xyz = points.ptr<float>();
  std::array<uchar, 1024> scratch;  // marks of a piece of a run when only counting
  // Pixels of `pixels` clear of the plane (above it; either side when glued_share is on: the floor past
  // the table's edge), marked in `image` (nullptr: counted only). Runs go in pieces that fit the scratch
  // line (a run crosses rows where a patch spans them).
  const auto clear_of = [&](const std::vector<int>& pixels, uchar* image) {
    int count = 0;
    constexpr int kPiece = static_cast<int>(scratch.size());
    for_each_pixel_run(pixels, [&](int first, int n) {
      for (int begin = first; begin < first + n; begin += kPiece)
        count += mark_off_plane(xyz + 3 * static_cast<size_t>(begin), std::min(kPiece, first + n - begin),
                                plane.normal.x(), plane.normal.y(), plane.normal.z(), plane.offset,
                                static_cast<float>(params.plane_band), glued(params), image ? image + begin : scratch.data());
    });
    return count;
  };
  cv::Mat clear;  // core pixels of table patches clear of the plane
  int cut = 0;
  for (const int p : patches_near(patches, points, plane, params, table_share(params))) {
    const auto& pixels = patches[static_cast<size_t>(p)].pixels;
    const int count = clear_of(pixels, nullptr);
    if (count < min_px) continue;
    if (clear.empty()) clear = cv::Mat(patch_labels.size(), CV_8U, cv::Scalar(0));
    clear_of(pixels, clear.ptr<uchar>());
    cut += count;
  }
  if (cut > 0) separate_marked(edges, clear, patch_labels);
  return cut;
}

int split_at_planes(cv::Mat& edges, const std::vector<Patch>& patches, const cv::Mat& patch_labels, const cv::Mat& points,
                    double band, int min_px, const std::optional<Plane>& table, const Params::Support& support) {
  const auto* pts = points.ptr<cv::Vec3f>();
  cv::Mat off;  // pixels of flat patches off their dominant plane; made for the first patch to split
  int cut = 0;
  for (const Patch& patch : patches) {
    if (patch.curved || static_cast<int>(patch.pixels.size()) < 2 * min_px) continue;  // a plane to split at
    if (table && is_near(patch, points, *table, support)) continue;  // cut_off_table splits it at the table
    Plane plane;
    if (dominant_plane(patch.pixels, points, band, plane) < 0.6) continue;
    const std::vector<int> outside = off_plane(patch.pixels, pts, plane, band);
    if (static_cast<int>(outside.size()) < min_px) continue;
    if (off.empty()) off = cv::Mat(patch_labels.size(), CV_8U, cv::Scalar(0));
    for (int i : outside) off.ptr<uchar>()[i] = 255;
    cut += static_cast<int>(outside.size());
  }
  if (cut > 0) separate_marked(edges, off, patch_labels);
  return cut;
}

int release_from_table(cv::Mat& assigned_labels, const std::vector<int>& edge_pixels, const std::vector<Patch>& patches,
                       const cv::Mat& points, const Plane& plane, const Params::Support& params) {
  const auto* pts = points.ptr<cv::Vec3f>();
  int* lab = assigned_labels.ptr<int>();
  const int total = static_cast<int>(assigned_labels.total()), num_patches = static_cast<int>(patches.size());
  const float a = plane.normal.x(), b = plane.normal.y(), c = plane.normal.z(), d = plane.offset;
  const auto k = static_cast<float>(params.pixel_band);
  std::vector<std::uint8_t> table(static_cast<size_t>(num_patches) + 1, 0);
  for (int p = 0; p < num_patches; ++p) table[static_cast<size_t>(p) + 1] = patches[static_cast<size_t>(p)].table;
  // Only edge pixels can be released, and step d) lists the ones it labelled.
  int released = 0;
  for (const int i : edge_pixels) {
    if (i < 0 || i >= total) throw Error("release_from_table: edge pixel out of range");
    const int l = lab[i];
    if (l <= 0 || l > num_patches) continue;  // no patch
    const float x = pts[i][0], y = pts[i][1], z = pts[i][2];
    if (!table[static_cast<size_t>(l)] || a * x + b * y + c * z + d <= k * std::max(1.f, z * z)) continue;
    lab[i] = 0;
    ++released;
  }
  return released;
}

int settle_table(std::vector<Patch>& patches, const std::vector<std::pair<int, int>>& adjacent,
                          std::vector<int>& object_of_patch, std::vector<float>& cut_cost) {
  const int n = static_cast<int>(patches.size());
  if (static_cast<int>(object_of_patch.size()) != n) throw Error("absorb_enclosed_table: one object per patch expected");
  // Groups of table patches adjacent to each other (union-find, path halving).
  std::vector<int> parent(static_cast<size_t>(n));
  std::iota(parent.begin(), parent.end(), 0);
  const auto root = [&](int v) { return find_root(parent, v); };
  const auto table = [&](int p) { return patches[static_cast<size_t>(p)].table; };
  for (const auto& [a, b] : adjacent)
    if (table(a) && table(b)) parent[static_cast<size_t>(root(a))] = root(b);
  int largest = -1;
  for (int p = 0; p < n; ++p)
    if (table(p) && (largest < 0 || patches[static_cast<size_t>(p)].pixels.size() > patches[static_cast<size_t>(largest)].pixels.size())) largest = p;
  if (largest < 0) return 0;
  // Per group: the one object all its non-table neighbours belong to (-1: none yet, -2: several).
  std::vector<int> neighbour_object(static_cast<size_t>(n), -1);
  for (const auto& [a, b] : adjacent) {
    if (table(a) == table(b)) continue;
    const int group = root(table(a) ? a : b), object = object_of_patch[static_cast<size_t>(table(a) ? b : a)];
    int& seen = neighbour_object[static_cast<size_t>(group)];
    seen = seen == -1 || seen == object ? object : -2;
  }
  // Enclosed: the group lies inside the image box of that object's patches.
  std::vector<cv::Rect> object_box(cut_cost.size()), group_box(static_cast<size_t>(n));
  for (int p = 0; p < n; ++p) {
    cv::Rect& box = table(p) ? group_box[static_cast<size_t>(root(p))] : object_box[static_cast<size_t>(object_of_patch[static_cast<size_t>(p)])];
    box = box.empty() ? patches[static_cast<size_t>(p)].bbox : box | patches[static_cast<size_t>(p)].bbox;
  }
  int absorbed = 0;
  for (int p = 0; p < n; ++p) {
    const int group = root(p), object = neighbour_object[static_cast<size_t>(group)];
    if (!table(p) || group == root(largest) || object < 0) continue;
    const cv::Rect& inner = group_box[static_cast<size_t>(group)];
    if ((inner & object_box[static_cast<size_t>(object)]) != inner) continue;
    patches[static_cast<size_t>(p)].table = false;
    object_of_patch[static_cast<size_t>(p)] = object;
    ++absorbed;
  }
  // The other pieces are one object: the table (pieces the objects on it cut apart are not linked).
  const int table_object = object_of_patch[static_cast<size_t>(largest)];
  for (int p = 0; p < n; ++p)
    if (table(p)) object_of_patch[static_cast<size_t>(p)] = table_object;
  // Objects without a patch left are removed; the others keep their order.
  std::vector<int> new_id(cut_cost.size(), -1);
  for (int o : object_of_patch) new_id[static_cast<size_t>(o)] = 0;
  int next = 0;
  std::vector<float> kept;
  for (size_t o = 0; o < new_id.size(); ++o)
    if (new_id[o] == 0) {
      new_id[o] = next++;
      kept.push_back(cut_cost[o]);
    }
  for (int& o : object_of_patch) o = new_id[static_cast<size_t>(o)];
  cut_cost = std::move(kept);
  return absorbed;
}

int claim_enclosed_floors(cv::Mat& object_labels, const cv::Mat& patch_labels, std::vector<Patch>& patches,
                          std::vector<int>& object_of_patch, int reach_px, int ring_px, double share) {
  if (share <= 0 || ring_px <= 0) return 0;
  if (object_labels.type() != CV_32S || patch_labels.type() != CV_32S || object_labels.size() != patch_labels.size() ||
      object_of_patch.size() != patches.size())
    throw Error("claim_enclosed_floors: CV_32S object and patch images of one size and one object per patch expected");
  int largest = -1;
  for (int p = 0; p < static_cast<int>(patches.size()); ++p)
    if (patches[static_cast<size_t>(p)].table &&
        (largest < 0 || patches[static_cast<size_t>(p)].pixels.size() > patches[static_cast<size_t>(largest)].pixels.size()))
      largest = p;
  if (largest < 0) return 0;
  const int table_label = object_of_patch[static_cast<size_t>(largest)] + 1;
  const cv::Rect image(0, 0, patch_labels.cols, patch_labels.rows);
  const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, {2 * ring_px + 1, 2 * ring_px + 1});  // separable: fast
  int claimed = 0;
  for (int p = 0; p < static_cast<int>(patches.size()); ++p) {
    Patch& patch = patches[static_cast<size_t>(p)];
    if (!patch.table || p == largest) continue;
    // The patch's box grown by the edge pixels it took (within reach_px of its core) and the ring: inside the image.
    const int grow = reach_px + ring_px + 1;
    const cv::Rect box(patch.bbox.x - grow, patch.bbox.y - grow, patch.bbox.width + 2 * grow, patch.bbox.height + 2 * grow);
    if ((box & image) != box) continue;
    const cv::Mat region = patch_labels(box) == patch.id;
    cv::Mat ring;
    cv::dilate(region, ring, kernel);
    ring &= ~region;
    std::map<int, int> count;  // object label -> ring pixels
    int ring_pixels = 0, unlabelled = 0;
    for (int y = 0; y < box.height; ++y) {
      const uchar* in_ring = ring.ptr<uchar>(y);
      const int* label = object_labels.ptr<int>(box.y + y) + box.x;
      for (int x = 0; x < box.width; ++x) {
        if (!in_ring[x]) continue;
        ++ring_pixels;
        if (label[x] == 0) ++unlabelled;
        else ++count[label[x]];
      }
    }
    const int labelled = ring_pixels - unlabelled;
    if (ring_pixels == 0 || 2 * labelled < ring_pixels) continue;
    const auto owner = std::max_element(count.begin(), count.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
    if (owner == count.end() || owner->first == table_label || owner->second < share * labelled) continue;
    cv::Mat labels = object_labels(box);
    labels.setTo(owner->first, region & (labels == table_label));
    patch.table = false;
    object_of_patch[static_cast<size_t>(p)] = owner->first - 1;
    ++claimed;
  }
  return claimed;
}

Support support_of(const Plane& plane, const std::vector<Patch>& patches, const cv::Mat& points,
                   const Params::Support& params) {
  std::vector<const std::vector<int>*> table_pixels;
  for (const auto& patch : patches)
    if (patch.table) table_pixels.push_back(&patch.pixels);
  const std::vector<int> sample = sample_of(table_pixels, points.ptr<cv::Vec3f>(), sample_budget(kRegionSample, points));
  return {plane, region_of_sample(plane, sample, points, params.region_margin)};
}

}  // namespace clutterseg
