// Per-object outputs: statistics, the support plane (table) and the objects-only view.
#include "clutterseg/objects.hpp"

#include <array>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

Eigen::Vector3d to_eigen(const cv::Vec3f& p) { return {p[0], p[1], p[2]}; }

// Least-squares plane of a pixel list (at most ~3000 of them used), normal facing the camera.
bool fit_plane(const std::vector<int>& pixels, const cv::Mat& points, Plane& plane) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t stride = std::max<size_t>(1, pixels.size() / 3000);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  int n = 0;
  for (size_t k = 0; k < pixels.size(); k += stride) {
    if (!valid_point(pts[pixels[k]])) continue;
    const Eigen::Vector3d q = to_eigen(pts[pixels[k]]);
    sum += q;
    outer += q * q.transpose();
    ++n;
  }
  if (n < 10) return false;
  const Eigen::Vector3d mean = sum / n;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(outer / n - mean * mean.transpose());
  if (eig.eigenvalues()(1) < 1e-8) return false;
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(mean) > 0) normal = -normal;
  plane.normal = normal.cast<float>();
  plane.offset = static_cast<float>(-normal.dot(mean));
  return true;
}

// The visible region of a support candidate: convex hull of its points projected into the plane,
// grown by a margin and rasterised at 1 cm so that the test per point is a lookup.
struct PlaneRegion {
  Plane plane;
  Eigen::Vector3f u, v;   // orthonormal basis of the plane
  cv::Point2f origin;     // plane coordinates [m] of cell (0, 0)
  cv::Mat cells;          // CV_8U, 255 = over the region
  static constexpr float kCell = 0.01f;  // [m]
  bool over(const Eigen::Vector3f& q) const {
    // Cell coordinates; negative ones are outside, so truncation serves as floor (no division, no floor
    // call: this runs for every sampled pixel of every object and candidate).
    const float fx = (u.dot(q) - origin.x) * (1.f / kCell), fy = (v.dot(q) - origin.y) * (1.f / kCell);
    if (!(fx >= 0 && fy >= 0 && fx < static_cast<float>(cells.cols) && fy < static_cast<float>(cells.rows))) return false;
    return cells.at<uchar>(static_cast<int>(fy), static_cast<int>(fx)) != 0;
  }
};

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
  std::array<float, 8> largest;
  for (int k = 0; k < 8; ++k) largest[static_cast<size_t>(k)] = largest_projection(xs.data(), ys.data(), n, kDx[k], kDy[k]);
  std::array<cv::Point2f, 8> extreme;
  for (int k = 0; k < 8; ++k) {
    const int first = first_at_least(xs.data(), ys.data(), n, kDx[k], kDy[k], largest[static_cast<size_t>(k)]);
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

PlaneRegion region_of(const Plane& plane, const std::vector<int>& pixels, const cv::Mat& points, double margin) {
  PlaneRegion r;
  r.plane = plane;
  r.u = plane.normal.unitOrthogonal();
  r.v = plane.normal.cross(r.u);
  const auto* pts = points.ptr<cv::Vec3f>();
  std::vector<cv::Point2f> projected;
  const size_t stride = std::max<size_t>(1, pixels.size() / 4000);
  for (size_t k = 0; k < pixels.size(); k += stride)
    if (valid_point(pts[pixels[k]])) {
      const Eigen::Vector3f q = to_eigen(pts[pixels[k]]).cast<float>();
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

// Share of a patch's points within `band` of its least-squares plane (flatness that does not depend
// on the normal histogram, which noise spreads on large, far surfaces).
double inlier_share(const std::vector<int>& pixels, const cv::Mat& points, const Plane& plane, double band) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t stride = std::max<size_t>(1, pixels.size() / 2000);
  int in = 0, n = 0;
  for (size_t k = 0; k < pixels.size(); k += stride) {
    if (!valid_point(pts[pixels[k]])) continue;
    ++n;
    in += std::abs(plane.distance(to_eigen(pts[pixels[k]]).cast<float>())) <= band;
  }
  return n ? static_cast<double>(in) / n : 0.0;
}

// inlier_share(...) >= share, the same points visited, but it stops once the points left could not
// lift the share to `share` even if all were inliers (most patches are far from the table's plane).
bool mostly_within(const std::vector<int>& pixels, const cv::Mat& points, const Plane& plane, double band, double share) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t stride = std::max<size_t>(1, pixels.size() / 2000);
  const size_t visits = (pixels.size() + stride - 1) / stride;
  int in = 0, n = 0;
  for (size_t v = 0; v < visits; ++v) {
    const int i = pixels[v * stride];
    if (!valid_point(pts[i])) continue;
    ++n;
    in += std::abs(plane.distance(to_eigen(pts[i]).cast<float>())) <= band;
    // Best final share (in + left) / (n + left); half a point of margin keeps rounding out of it.
    const double left = static_cast<double>(visits - v - 1);
    if (in + left < share * (n + left) - 0.5) return false;
  }
  return n && static_cast<double>(in) / n >= share;
}

// Points within band of the plane (Plane::distance up to rounding: the sum is in scan order, Eigen sums
// the last two products first; a point exactly at the band edge can count differently).
CLUTTERSEG_ROW_KERNEL int count_planar(const float* __restrict x, const float* __restrict y, const float* __restrict z,
                                       int n, float a, float b, float c, float offset, float band) {
  int count = 0;
  for (int k = 0; k < n; ++k) count += std::abs(a * x[k] + b * y[k] + c * z[k] + offset) <= band;
  return count;
}

// Valid points among n interleaved xyz points.
CLUTTERSEG_ROW_KERNEL int count_valid(const float* __restrict xyz, int n) {
  int count = 0;
  for (int k = 0; k < n; ++k) count += valid_depth(xyz[3 * k + 2]);
  return count;
}

// out[k] = value where point k (interleaved xyz) is valid and lies above the plane by more than `low`
// and at most `high` (Plane::distance, in a vectorised loop); other entries unchanged.
CLUTTERSEG_ROW_KERNEL void mark_between(const float* __restrict xyz, int n, float a, float b, float c, float offset,
                                        float low, float high, uchar value, uchar* __restrict out) {
  for (int k = 0; k < n; ++k) {
    const float x = xyz[3 * k], y = xyz[3 * k + 1], z = xyz[3 * k + 2];
    const float h = a * x + (b * y + c * z) + offset;  // Eigen's order for a 3-vector dot: same bits
    out[k] = valid_depth(z) ? ((h > low) & (h <= high) ? value : 0) : out[k];
  }
}

// The largest float <= v: for a float h, h > v and h <= v hold exactly when they hold for it, so a
// comparison with a double threshold can stay in float lanes.
float float_at_most(double v) {
  const float f = static_cast<float>(v);
  return static_cast<double>(f) > v ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}

void mark_above(const float* xyz, int n, const Plane& plane, double low, double high, uchar value, uchar* out) {
  mark_between(xyz, n, plane.normal.x(), plane.normal.y(), plane.normal.z(), plane.offset, float_at_most(low),
               float_at_most(high), value, out);
}

int count_within(const std::vector<float>& x, const std::vector<float>& y, const std::vector<float>& z,
                 const Plane& plane, float band) {
  return count_planar(x.data(), y.data(), z.data(), static_cast<int>(x.size()), plane.normal.x(), plane.normal.y(),
                      plane.normal.z(), plane.offset, band);
}

// Dominant plane of a patch: RANSAC over its points (a table patch may hold the foot of an object that
// the edges did not separate), refined by least squares on the inliers. Deterministic: the draws are
// seeded by the patch size. Returns the inlier share.
double dominant_plane(const std::vector<int>& pixels, const cv::Mat& points, double band, Plane& plane) {
  const auto* pts = points.ptr<cv::Vec3f>();
  std::vector<int> sample;
  const size_t stride = std::max<size_t>(1, pixels.size() / 1000);
  for (size_t k = 0; k < pixels.size(); k += stride)
    if (valid_point(pts[pixels[k]])) sample.push_back(pixels[k]);
  if (sample.size() < 10) return 0;
  std::vector<float> xs, ys, zs;  // contiguous planes: each of the 30 draws counts over all of them
  for (int i : sample) {
    xs.push_back(pts[i][0]);
    ys.push_back(pts[i][1]);
    zs.push_back(pts[i][2]);
  }
  std::uint64_t state = 0x9e3779b97f4a7c15ULL ^ pixels.size();
  auto next = [&] {  // xorshift64: a small, portable, seeded generator
    state ^= state << 13; state ^= state >> 7; state ^= state << 17;
    return static_cast<size_t>(state % sample.size());
  };
  int best_count = -1;
  Plane best;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Eigen::Vector3f a = to_eigen(pts[sample[next()]]).cast<float>();
    const Eigen::Vector3f b = to_eigen(pts[sample[next()]]).cast<float>();
    const Eigen::Vector3f c = to_eigen(pts[sample[next()]]).cast<float>();
    Eigen::Vector3f n = (b - a).cross(c - a);
    if (n.norm() < 1e-9f) continue;
    n.normalize();
    if (n.dot(a) > 0) n = -n;
    Plane candidate{n, -n.dot(a)};
    const int count = count_within(xs, ys, zs, candidate, static_cast<float>(band));
    if (count > best_count) { best_count = count; best = candidate; }
  }
  if (best_count <= 0) return 0;
  std::vector<int> inliers;
  for (int i : sample)
    if (std::abs(best.distance(to_eigen(pts[i]).cast<float>())) <= band) inliers.push_back(i);
  plane = best;
  if (fit_plane(inliers, points, plane)) {
    const double share = inlier_share(sample, points, plane, band);
    if (share >= static_cast<double>(best_count) / sample.size()) return share;
  }
  plane = best;
  return static_cast<double>(best_count) / sample.size();
}

// Pixels visited per object when classifying it against the table (a share is all we need).
constexpr int kSamplesPerObject = 500;

struct Heights {
  int samples = 0, in_band = 0, above_max = 0, below = 0, over_region = 0;
};

// Calls visit(object, begin, end) for every run of equal labels 1..num_objects in scan order: pixels
// [begin, end) of object `object` (0-based). Labels come in long runs (an object's row segments), so
// per-object sums can live in registers for a run.
template <class Visit>
void for_each_run(const cv::Mat& object_labels, int num_objects, Visit visit) {
  const int* lab = object_labels.ptr<int>();
  const int total = static_cast<int>(object_labels.total());
  for (int begin = 0; begin < total;) {
    const int id = lab[begin], end = run_end(lab, begin, total);
    if (id > 0 && id <= num_objects) visit(id - 1, begin, end);
    begin = end;
  }
}

// Sums over the valid points of a run, relative to `origin`: n, then x, y, z, then xx, xy, xz, yy, yz, zz.
// Coordinates come as planes (x, y, z), so that the loop vectorises (float lanes, OpenMP simd); relative
// to a point of the object the values are centimetres, so float sums of a run (at most one image row)
// lose nothing that matters.
CLUTTERSEG_AVX2_KERNEL void centred_sums(const float* __restrict px, const float* __restrict py,
                                        const float* __restrict pz, int count, const float* __restrict origin,
                                        double* __restrict total) {
  float n = 0, x = 0, y = 0, z = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  const float ox = origin[0], oy = origin[1], oz = origin[2];
#pragma omp simd reduction(+ : n, x, y, z, xx, xy, xz, yy, yz, zz)
  for (int k = 0; k < count; ++k) {
    const bool valid = valid_depth(pz[k]);
    const float dx = valid ? px[k] - ox : 0.f, dy = valid ? py[k] - oy : 0.f, dz = valid ? pz[k] - oz : 0.f;
    n += valid ? 1.f : 0.f;
    x += dx; y += dy; z += dz;
    xx += dx * dx; xy += dx * dy; xz += dx * dz; yy += dy * dy; yz += dy * dz; zz += dz * dz;
  }
  const float run[10] = {n, x, y, z, xx, xy, xz, yy, yz, zz};
  for (int k = 0; k < 10; ++k) total[k] += run[k];
}

// Lowest and highest values of axes * p over the valid points of a run (axes: row-major 3x3; points as
// planes).
CLUTTERSEG_ROW_KERNEL void extents_along(const float* __restrict px, const float* __restrict py,
                                         const float* __restrict pz, int count, const float* __restrict axes,
                                         float* __restrict low, float* __restrict high) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  float lo0 = low[0], lo1 = low[1], lo2 = low[2], hi0 = high[0], hi1 = high[1], hi2 = high[2];
  const float a00 = axes[0], a01 = axes[1], a02 = axes[2], a10 = axes[3], a11 = axes[4], a12 = axes[5];
  const float a20 = axes[6], a21 = axes[7], a22 = axes[8];
#pragma omp simd reduction(min : lo0, lo1, lo2) reduction(max : hi0, hi1, hi2)
  for (int k = 0; k < count; ++k) {
    const bool valid = valid_depth(pz[k]);
    const float c0 = a00 * px[k] + a01 * py[k] + a02 * pz[k], c1 = a10 * px[k] + a11 * py[k] + a12 * pz[k];
    const float c2 = a20 * px[k] + a21 * py[k] + a22 * pz[k];
    lo0 = std::min(lo0, valid ? c0 : kInf); hi0 = std::max(hi0, valid ? c0 : -kInf);
    lo1 = std::min(lo1, valid ? c1 : kInf); hi1 = std::max(hi1, valid ? c1 : -kInf);
    lo2 = std::min(lo2, valid ? c2 : kInf); hi2 = std::max(hi2, valid ? c2 : -kInf);
  }
  low[0] = lo0; low[1] = lo1; low[2] = lo2;
  high[0] = hi0; high[1] = hi1; high[2] = hi2;
}

// First and second moments of an object's points, summed relative to its first valid point (centred
// sums: no cancellation between metre-sized squares in the covariance).
struct Moments {
  std::array<float, 3> origin{};
  bool has_origin = false;
  std::array<double, 10> sums{};  // n, x, y, z, xx, xy, xz, yy, yz, zz
  void add_run(const float* x, const float* y, const float* z, int count) {
    for (int k = 0; !has_origin && k < count; ++k)
      if (valid_depth(z[k])) {
        origin = {x[k], y[k], z[k]};
        has_origin = true;
      }
    if (has_origin) centred_sums(x, y, z, count, origin.data(), sums.data());
  }
  int valid() const { return static_cast<int>(sums[0]); }
};

// Pixel count, centroid and PCA box of the objects flagged in `redo` (statistics only: id, patches,
// cut cost and flags are left alone). Two passes: moments give the axes, then extents along them.
void describe_shapes(std::vector<Object>& objects, const std::vector<char>& redo, const cv::Mat& object_labels,
                     const cv::Mat& points, const Camera& camera) {
  // Coordinates as planes: the per-run loops below read them contiguously (and vectorise).
  cv::Mat planes[3];
  cv::split(points, planes);
  const float* px = planes[0].ptr<float>();
  const float* py = planes[1].ptr<float>();
  const float* pz = planes[2].ptr<float>();
  const int num_objects = static_cast<int>(objects.size());
  std::vector<Moments> moments(objects.size());
  struct Run {
    int object, begin, end;
  };
  std::vector<Run> runs;  // of the objects to redo, for the second pass
  for_each_run(object_labels, num_objects, [&](int o, int begin, int end) {
    if (!redo[static_cast<size_t>(o)]) return;
    runs.push_back({o, begin, end});
    objects[static_cast<size_t>(o)].pixel_count += end - begin;
    moments[static_cast<size_t>(o)].add_run(px + begin, py + begin, pz + begin, end - begin);
  });
  // Axes in the camera frame (rows of axes_t); float extents are plenty for millimetres at a few metres.
  const Eigen::Matrix3d rot = camera.camera_to_robot.topLeftCorner<3, 3>();
  const Eigen::Vector3d shift = camera.camera_to_robot.topRightCorner<3, 1>();
  std::vector<Eigen::Matrix3d> axes(objects.size(), Eigen::Matrix3d::Identity());
  std::vector<std::array<float, 9>> axes_t(objects.size(), {1, 0, 0, 0, 1, 0, 0, 0, 1});  // row-major
  for (size_t o = 0; o < objects.size(); ++o) {
    const Moments& m = moments[o];
    if (!redo[o] || m.valid() == 0) continue;
    const auto& s = m.sums;
    const Eigen::Vector3d offset = Eigen::Vector3d(s[1], s[2], s[3]) / s[0];  // mean - origin
    Eigen::Matrix3d second;
    second << s[4], s[5], s[6], s[5], s[7], s[8], s[6], s[8], s[9];
    const Eigen::Vector3d mean = Eigen::Vector3f(m.origin[0], m.origin[1], m.origin[2]).cast<double>() + offset;
    objects[o].centroid = (rot * mean + shift).cast<float>();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(second / s[0] - offset * offset.transpose());
    axes[o] = eig.eigenvectors();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) axes_t[o][static_cast<size_t>(3 * r + c)] = static_cast<float>(axes[o](c, r));
  }
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<Eigen::Vector3f> low(objects.size(), Eigen::Vector3f::Constant(kInf));
  std::vector<Eigen::Vector3f> high(objects.size(), Eigen::Vector3f::Constant(-kInf));
  for (const auto& [o, begin, end] : runs) {
    const auto k = static_cast<size_t>(o);
    extents_along(px + begin, py + begin, pz + begin, end - begin, axes_t[k].data(), low[k].data(), high[k].data());
  }
  for (size_t o = 0; o < objects.size(); ++o) {
    if (!redo[o] || moments[o].valid() == 0) continue;
    // Axes ordered by extent, largest first, and right-handed.
    const Eigen::Vector3d lo = low[o].cast<double>(), hi = high[o].cast<double>();
    const Eigen::Vector3d extent = hi - lo;
    std::array<int, 3> order = {0, 1, 2};
    std::sort(order.begin(), order.end(), [&](int a, int b) { return extent(a) > extent(b); });
    OrientedBox& box = objects[o].box;
    for (int k = 0; k < 3; ++k) {
      box.axes.col(k) = (rot * axes[o].col(order[static_cast<size_t>(k)])).cast<float>();
      box.extents(k) = static_cast<float>(extent(order[static_cast<size_t>(k)]));
    }
    // Eigenvectors come with an arbitrary sign that rounding can flip: the largest component of the
    // first two axes is made positive, so that the same object gets the same box.
    for (int k = 0; k < 2; ++k) {
      Eigen::Index largest = 0;
      box.axes.col(k).cwiseAbs().maxCoeff(&largest);
      if (box.axes(largest, k) < 0) box.axes.col(k) = -box.axes.col(k);
    }
    box.axes.col(2) = box.axes.col(0).cross(box.axes.col(1));
    box.center = (rot * (axes[o] * (0.5 * (lo + hi))) + shift).cast<float>();
  }
}

}  // namespace

std::vector<Object> describe_objects(const cv::Mat& object_labels, const cv::Mat& points,
                                     const std::vector<int>& object_of_patch,
                                     const std::vector<float>& cut_cost, const Camera& camera) {
  if (object_labels.type() != CV_32S || points.type() != CV_32FC3 || object_labels.size() != points.size())
    throw Error("describe_objects: labels must be CV_32S and points CV_32FC3 of the same size");
  int count = 0;  // the largest label (a plain loop: cv::minMaxLoc is several times slower)
  const int* lab = object_labels.ptr<int>();
  const size_t total = object_labels.total();
  for (size_t i = 0; i < total; ++i) count = std::max(count, lab[i]);
  std::vector<Object> objects(static_cast<size_t>(std::max(0, count)));
  describe_shapes(objects, std::vector<char>(objects.size(), 1), object_labels, points, camera);
  for (size_t o = 0; o < objects.size(); ++o) {
    objects[o].id = static_cast<int>(o) + 1;
    objects[o].cut_cost = o < cut_cost.size() ? cut_cost[o] : std::numeric_limits<float>::infinity();
  }
  for (size_t p = 0; p < object_of_patch.size(); ++p) {
    const int o = object_of_patch[p];
    if (o >= 0 && o < count) objects[static_cast<size_t>(o)].patches.push_back(static_cast<int>(p));
  }
  return objects;
}

std::optional<Plane> find_support(std::vector<Object>& objects, const std::vector<Patch>& patches,
                                  const cv::Mat& object_labels, const cv::Mat& points,
                                  const Params::Support& params) {
  if (object_labels.type() != CV_32S || points.type() != CV_32FC3 || object_labels.size() != points.size())
    throw Error("find_support: labels must be CV_32S and points CV_32FC3 of the same size");
  const int* lab = object_labels.ptr<int>();
  const auto* pts = points.ptr<cv::Vec3f>();
  const int num_objects = static_cast<int>(objects.size());
  auto object_of_pixel = [&](int i) { return lab[i] > 0 && lab[i] <= num_objects ? lab[i] - 1 : -1; };

  // Pixels of every object, visited with a stride (bounded work per object and candidate).
  std::vector<std::vector<int>> samples(objects.size());
  int valid_total = 0;  // labelled pixels (valid or not)
  {
    std::vector<int> countdown(objects.size(), 0);
    for_each_run(object_labels, num_objects, [&](int o, int begin, int end) {
      valid_total += end - begin;
      const int stride = std::max(1, objects[static_cast<size_t>(o)].pixel_count / kSamplesPerObject);
      int& wait = countdown[static_cast<size_t>(o)];
      auto& picked = samples[static_cast<size_t>(o)];
      if (count_valid(&pts[begin][0], end - begin) == end - begin) {  // the common case: every stride-th pixel
        int i = begin + wait;
        for (; i < end; i += stride) picked.push_back(i);
        wait = i - end;
        return;
      }
      for (int i = begin; i < end; ++i) {
        if (!valid_point(pts[i]) || wait-- > 0) continue;
        wait = stride - 1;
        picked.push_back(i);
      }
    });
  }

  // Candidates: the 4 largest flat patches with >= 2 % of the labelled pixels. Patches are judged
  // largest first (ties: lower index), so RANSAC runs only until 4 are found.
  std::vector<int> by_size;
  for (size_t p = 0; p < patches.size(); ++p)
    if (static_cast<double>(patches[p].pixels.size()) >= 0.02 * valid_total) by_size.push_back(static_cast<int>(p));
  std::stable_sort(by_size.begin(), by_size.end(), [&](int a, int b) {
    return patches[static_cast<size_t>(a)].pixels.size() > patches[static_cast<size_t>(b)].pixels.size();
  });
  std::vector<int> candidates;
  std::vector<Plane> planes;  // per candidate
  for (size_t k = 0; k < by_size.size() && candidates.size() < 4; ++k) {
    Plane plane;
    if (dominant_plane(patches[static_cast<size_t>(by_size[k])].pixels, points, params.plane_band, plane) < 0.6) continue;
    candidates.push_back(by_size[k]);
    planes.push_back(plane);
  }
  if (candidates.empty()) return std::nullopt;
  // Candidate index + 1 of every candidate pixel, 0 elsewhere.
  cv::Mat candidate_mark(object_labels.size(), CV_8U, cv::Scalar(0));
  uchar* mark = candidate_mark.ptr<uchar>();
  for (size_t k = 0; k < candidates.size(); ++k)
    for (int i : patches[static_cast<size_t>(candidates[k])].pixels) mark[i] = static_cast<uchar>(k + 1);
  std::vector<int> object_of_candidate;
  for (int c : candidates) {
    const auto& px = patches[static_cast<size_t>(c)].pixels;
    object_of_candidate.push_back(px.empty() ? -1 : object_of_pixel(px[px.size() / 2]));
  }

  // Score: pixels of objects resting on the candidate (touching it, over its visible region), between
  // the plane band and max_height on its camera-facing side. Objects holding a candidate (other large planes) do not
  // count, so a wall does not score the table in front of it.
  auto heights = [&](int o, const PlaneRegion& region) {
    Heights h;
    for (int i : samples[static_cast<size_t>(o)]) {
      const Eigen::Vector3f q(pts[i][0], pts[i][1], pts[i][2]);
      const float d = region.plane.distance(q);
      ++h.samples;
      h.in_band += std::abs(d) <= params.plane_band;
      h.above_max += d > params.max_height;
      h.below += d < -params.plane_band;
      h.over_region += region.over(q);
    }
    return h;
  };
  int best = -1;
  double best_score = -1;
  PlaneRegion best_region;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const Plane& plane = planes[k];
    const auto& px = patches[static_cast<size_t>(candidates[k])].pixels;
    const PlaneRegion region = region_of(plane, px, points, params.region_margin);
    double score = 0;
    for (int o = 0; o < num_objects; ++o) {
      // Other large planes (walls, other tables) are not mass on this one; the candidate's own object
      // counts (objects the edges did not separate from the table stand on it).
      if (o != object_of_candidate[k] &&
          std::find(object_of_candidate.begin(), object_of_candidate.end(), o) != object_of_candidate.end()) continue;
      // An object rests on the plane when its lowest point over the region is within contact_distance
      // (a box in front of a wall floats 20 cm off it).
      int resting = 0;
      float lowest = std::numeric_limits<float>::infinity();
      for (int i : samples[static_cast<size_t>(o)]) {
        if (mark[i] && mark[i] != static_cast<uchar>(k + 1)) continue;  // another large plane
        const Eigen::Vector3f q(pts[i][0], pts[i][1], pts[i][2]);
        const float d = plane.distance(q);
        if (d <= -params.plane_band || d > params.max_height || !region.over(q)) continue;
        lowest = std::min(lowest, d);
        resting += d > params.plane_band;
      }
      if (lowest > params.contact_distance) continue;
      // Back to pixel units: samples are a stride of the object's pixels.
      if (!samples[static_cast<size_t>(o)].empty())
        score += static_cast<double>(resting) / samples[static_cast<size_t>(o)].size() * objects[static_cast<size_t>(o)].pixel_count;
    }
    if (score > best_score) { best_score = score; best = static_cast<int>(k); best_region = region; }
  }
  if (best < 0) return std::nullopt;
  // The table's visible region: every patch lying in its plane (objects split the table into pieces;
  // objects at the back stand on pieces other than the largest).
  {
    std::vector<int> table_pixels;
    for (const auto& patch : patches)
      if (mostly_within(patch.pixels, points, best_region.plane, params.plane_band, 0.8))
        table_pixels.insert(table_pixels.end(), patch.pixels.begin(), patch.pixels.end());
    best_region = region_of(best_region.plane, table_pixels, points, params.region_margin);
  }
  const Plane& plane = best_region.plane;
  const Eigen::Vector3f up = plane.normal;

  for (int o = 0; o < num_objects; ++o) {
    Object& object = objects[static_cast<size_t>(o)];
    if (o == object_of_candidate[static_cast<size_t>(best)]) { object.support = true; continue; }
    const Heights h = heights(o, best_region);
    if (h.samples == 0) continue;
    const double n = h.samples;
    // Other pieces of the table (split off by occluding objects) lie in its plane.
    if (h.in_band >= 0.8 * n) { object.support = true; continue; }
    if (h.above_max > 0.5 * n || h.below > 0.5 * n || h.over_region < 0.3 * n) { object.background = true; continue; }
    // Walls: large and flat, standing roughly perpendicular to the table (the size first: it is known).
    if (object.box.extents(0) < params.wall_min_extent) continue;
    int largest = -1;
    for (int p : object.patches)
      if (largest < 0 || patches[static_cast<size_t>(p)].pixels.size() > patches[static_cast<size_t>(largest)].pixels.size()) largest = p;
    Plane own;
    if (largest >= 0 && fit_plane(patches[static_cast<size_t>(largest)].pixels, points, own) &&
        mostly_within(patches[static_cast<size_t>(largest)].pixels, points, own, params.plane_band, 0.9) &&
        std::abs(own.normal.dot(up)) < std::cos(60.0 * M_PI / 180.0))
      object.background = true;
  }
  return plane;
}

int split_support(cv::Mat& object_labels, std::vector<Object>& objects, const Plane& table, const cv::Mat& points,
                  const Params::Support& params, int min_px, const Camera& camera) {
  if (object_labels.type() != CV_32S || points.type() != CV_32FC3 || object_labels.size() != points.size())
    throw Error("split_support: labels must be CV_32S and points CV_32FC3 of the same size");
  const int num_objects = static_cast<int>(objects.size());
  int* lab = object_labels.ptr<int>();
  const auto* pts = points.ptr<cv::Vec3f>();
  // Pixels of support objects clear of the table: candidates for the groups below.
  constexpr uchar kClear = 255, kQueued = 1;
  cv::Mat clear(object_labels.size(), CV_8U, cv::Scalar(0));
  uchar* mask = clear.ptr<uchar>();
  for_each_run(object_labels, num_objects, [&](int o, int begin, int end) {
    if (objects[static_cast<size_t>(o)].support)
      mark_above(&pts[begin][0], end - begin, table, params.plane_band, params.max_height, kClear, mask + begin);
  });
  // Groups: 8-connected, and neighbours closer than plane_band in 3D (a box in front of a keyboard is
  // not one object with it). Each pixel enters the queue once: bounded.
  std::vector<int> queue;
  std::vector<char> lost(objects.size(), 0);  // objects that gave pixels to a new one
  const float link2 = static_cast<float>(params.plane_band * params.plane_band);
  const int width = object_labels.cols, height = object_labels.rows, total = width * height;
  int next = num_objects, added = 0;
  std::vector<std::vector<int>> new_pixels;
  // Seeds by memchr: clear pixels are few and it scans many bytes per step.
  auto next_clear = [&](int from) {
    const void* found = std::memchr(mask + from, kClear, static_cast<size_t>(total - from));
    return found ? static_cast<int>(static_cast<const uchar*>(found) - mask) : total;
  };
  for (int start = next_clear(0); start < total; start = next_clear(start + 1)) {
    queue.assign(1, start);
    mask[start] = kQueued;
    for (size_t head = 0; head < queue.size(); ++head) {
      const int i = queue[head], x = i % width, y = i / width;
      const bool interior = x > 0 && y > 0 && x + 1 < width && y + 1 < height;  // no border tests
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int xx = x + dx, yy = y + dy, j = yy * width + xx;
          if (!interior && (xx < 0 || yy < 0 || xx >= width || yy >= height)) continue;
          if (mask[j] != kClear) continue;
          const cv::Vec3f d = pts[i] - pts[j];
          if (d.dot(d) >= link2) continue;
          mask[j] = kQueued;
          queue.push_back(j);
        }
    }
    if (static_cast<int>(queue.size()) < min_px) continue;
    const int id = ++next;
    ++added;
    new_pixels.push_back(queue);
    for (int i : queue) {
      lost[static_cast<size_t>(lab[i] - 1)] = 1;
      lab[i] = id;
    }
  }
  if (added == 0) return 0;
  // Statistics again for the objects that changed (the support objects that lost pixels, the new ones);
  // the others keep theirs, which come from the same pixels.
  std::vector<char> redo(static_cast<size_t>(num_objects + added), 1);
  for (int o = 0; o < num_objects; ++o) {
    redo[static_cast<size_t>(o)] = lost[static_cast<size_t>(o)];
    if (!lost[static_cast<size_t>(o)]) continue;
    Object& object = objects[static_cast<size_t>(o)];
    object.pixel_count = 0;
    object.centroid = Eigen::Vector3f::Zero();
    object.box = OrientedBox{};
  }
  objects.resize(static_cast<size_t>(num_objects + added));
  for (int o = num_objects; o < num_objects + added; ++o) {
    objects[static_cast<size_t>(o)].id = o + 1;
    objects[static_cast<size_t>(o)].cut_cost = std::numeric_limits<float>::infinity();
  }
  describe_shapes(objects, redo, object_labels, points, camera);
  // A wall standing on the table's edge came with it: large, flat and perpendicular to the table.
  for (size_t k = 0; k < new_pixels.size(); ++k) {
    Object& object = objects[static_cast<size_t>(num_objects) + k];
    Plane own;
    object.background = object.box.extents(0) >= params.wall_min_extent && fit_plane(new_pixels[k], points, own) &&
                        mostly_within(new_pixels[k], points, own, params.plane_band, 0.9) &&
                        std::abs(own.normal.dot(table.normal)) < std::cos(60.0 * M_PI / 180.0);
  }
  return added;
}

cv::Mat objects_only(const cv::Mat& object_labels, const std::vector<Object>& objects) {
  // New ids keep the order of the old ones, so the view is as stable as the labels it comes from.
  std::vector<int> new_id(objects.size() + 1, 0);
  int next = 0;
  for (const auto& o : objects)
    if (!o.support && !o.background && o.id > 0 && o.id < static_cast<int>(new_id.size())) new_id[static_cast<size_t>(o.id)] = ++next;
  cv::Mat out(object_labels.size(), CV_32S);
  const int last = static_cast<int>(new_id.size()) - 1;
  for (int y = 0; y < object_labels.rows; ++y) {
    const int* lab = object_labels.ptr<int>(y);
    int* view = out.ptr<int>(y);
    for (int x = 0; x < object_labels.cols; ++x) view[x] = lab[x] > 0 && lab[x] <= last ? new_id[static_cast<size_t>(lab[x])] : 0;
  }
  return out;
}

}  // namespace clutterseg
