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
#include "clutterseg/support.hpp"

namespace clutterseg {

namespace {

// Valid points among n interleaved xyz points.
CLUTTERSEG_ROW_KERNEL int count_valid(const float* __restrict xyz, int n) {
  int count = 0;
  for (int k = 0; k < n; ++k) count += valid_depth(xyz[3 * k + 2]);
  return count;
}

// x, y, z of n interleaved points into three planes: cv::split, in fewer instructions (a vectorised
// stride-3 load).
CLUTTERSEG_ROW_KERNEL void deinterleave(const float* __restrict xyz, int n, float* __restrict x, float* __restrict y,
                                        float* __restrict z) {
  for (int i = 0; i < n; ++i) {
    x[i] = xyz[3 * i];
    y[i] = xyz[3 * i + 1];
    z[i] = xyz[3 * i + 2];
  }
}

// Extent of the valid points of `pixels` (a stride of at most ~2000) along the unit `direction` [m].
float length_along(const std::vector<int>& pixels, const cv::Mat& points, const Eigen::Vector3f& direction) {
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t stride = std::max<size_t>(1, pixels.size() / sample_budget(2000, points));
  float low = std::numeric_limits<float>::infinity(), high = -low;
  for (size_t k = 0; k < pixels.size(); k += stride) {
    const cv::Vec3f& q = pts[pixels[k]];
    if (!valid_point(q)) continue;
    const float t = direction.x() * q[0] + direction.y() * q[1] + direction.z() * q[2];
    low = std::min(low, t);
    high = std::max(high, t);
  }
  return high > low ? high - low : 0.f;
}

// Pixels visited per object when classifying it against the table (a share is all we need).
constexpr int kSamplesPerObject = 500;

struct Heights {
  int samples = 0, above_max = 0, below = 0, over_region = 0, near_table = 0;
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

// A run of pixels [begin, end) of one object (0-based), in scan order.
struct Run {
  int object, begin, end;
};

// The runs of every label > 0 (the largest label decides the number of objects: one pass, not two).
std::vector<Run> runs_of(const cv::Mat& object_labels) {
  std::vector<Run> runs;
  for_each_run(object_labels, std::numeric_limits<int>::max(), [&](int o, int begin, int end) { runs.push_back({o, begin, end}); });
  return runs;
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

// An object's lowest and highest values of axes * p (axes: rows of a row-major 3x3), per lane of 8. Min and
// max need no order, so a run is read in whole blocks of 8 (its last block overlapping the one before): no
// scalar tail and no merge of the lanes per run (runs are short, ~120 px at 640x480); the lanes are merged
// once per object.
constexpr int kLanes = 8;
struct Extents {
  float low[3][kLanes], high[3][kLanes];
  Extents() {
    for (int c = 0; c < 3; ++c) {
      std::fill_n(low[c], kLanes, std::numeric_limits<float>::infinity());
      std::fill_n(high[c], kLanes, -std::numeric_limits<float>::infinity());
    }
  }
  float lowest(int c) const { return *std::min_element(low[c], low[c] + kLanes); }
  float highest(int c) const { return *std::max_element(high[c], high[c] + kLanes); }
};

using Float8 = float __attribute__((vector_size(32)));
using Int8 = int __attribute__((vector_size(32)));

// Adds the valid points of a run (as planes) to `extents`.
CLUTTERSEG_AVX2_KERNEL void extents_along(const float* __restrict px, const float* __restrict py,
                                         const float* __restrict pz, int count, const float* __restrict axes,
                                         Extents& extents) {
  if (count < kLanes) {  // a short run: one lane
    for (int k = 0; k < count; ++k) {
      if (!valid_depth(pz[k])) continue;
      for (int c = 0; c < 3; ++c) {
        const float v = axes[3 * c] * px[k] + axes[3 * c + 1] * py[k] + axes[3 * c + 2] * pz[k];
        extents.low[c][0] = std::min(extents.low[c][0], v);
        extents.high[c][0] = std::max(extents.high[c][0], v);
      }
    }
    return;
  }
  Float8 low[3], high[3];
  for (int c = 0; c < 3; ++c) {
    std::memcpy(&low[c], extents.low[c], sizeof(Float8));
    std::memcpy(&high[c], extents.high[c], sizeof(Float8));
  }
  const Float8 zero = {}, inf = zero + std::numeric_limits<float>::infinity();
  const Float8 nan = zero + std::numeric_limits<float>::quiet_NaN();
  const auto add_block = [&](int k) {
    Float8 x, y, z;
    std::memcpy(&x, px + k, sizeof x);
    std::memcpy(&y, py + k, sizeof y);
    std::memcpy(&z, pz + k, sizeof z);
    // An invalid point (valid_depth, lane by lane) projects to NaN, which both compares below leave out.
    const Int8 valid = (z > zero) & (z < inf);
    x = valid ? x : nan;
#pragma GCC unroll 3
    for (int c = 0; c < 3; ++c) {
      const Float8 v = axes[3 * c] * x + axes[3 * c + 1] * y + axes[3 * c + 2] * z;
      low[c] = v < low[c] ? v : low[c];
      high[c] = high[c] < v ? v : high[c];
    }
  };
  int k = 0;
  for (; k + kLanes <= count; k += kLanes) add_block(k);
  if (k < count) add_block(count - kLanes);
  for (int c = 0; c < 3; ++c) {
    std::memcpy(extents.low[c], &low[c], sizeof(Float8));
    std::memcpy(extents.high[c], &high[c], sizeof(Float8));
  }
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

// Pixel count, centroid and PCA box of the objects flagged in `redo` from their runs (statistics only:
// id, patches, cut cost and flags are left alone). Two passes: moments give the axes, then extents along them.
void describe_shapes(std::vector<Object>& objects, const std::vector<char>& redo, const std::vector<Run>& runs,
                     const cv::Mat& points, const Camera& camera) {
  // Coordinates as planes: the per-run loops below read them contiguously (and vectorise).
  const cv::Mat cloud = points.isContinuous() ? points : points.clone();  // read as one array (an ROI is not)
  cv::Mat planes[3] = {cv::Mat(points.size(), CV_32F), cv::Mat(points.size(), CV_32F), cv::Mat(points.size(), CV_32F)};
  deinterleave(cloud.ptr<float>(), static_cast<int>(cloud.total()), planes[0].ptr<float>(), planes[1].ptr<float>(),
               planes[2].ptr<float>());
  const float* px = planes[0].ptr<float>();
  const float* py = planes[1].ptr<float>();
  const float* pz = planes[2].ptr<float>();
  std::vector<Moments> moments(objects.size());
  for (const auto& [o, begin, end] : runs) {
    if (!redo[static_cast<size_t>(o)]) continue;
    objects[static_cast<size_t>(o)].pixel_count += end - begin;
    moments[static_cast<size_t>(o)].add_run(px + begin, py + begin, pz + begin, end - begin);
  }
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
  std::vector<Extents> extents(objects.size());
  for (const auto& [o, begin, end] : runs) {
    const auto k = static_cast<size_t>(o);
    if (!redo[k]) continue;
    extents_along(px + begin, py + begin, pz + begin, end - begin, axes_t[k].data(), extents[k]);
  }
  for (size_t o = 0; o < objects.size(); ++o) {
    if (!redo[o] || moments[o].valid() == 0) continue;
    // Axes ordered by extent, largest first, and right-handed.
    const Extents& e = extents[o];
    const Eigen::Vector3d lo(e.lowest(0), e.lowest(1), e.lowest(2)), hi(e.highest(0), e.highest(1), e.highest(2));
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

// Share of object `id`'s outline near its face (its label's ends along rows and columns, within
// 4 * reach pixels of the face's bounding box) behind which, within `reach` pixels, the first measured
// point is at least 10 % farther from the camera (sampled). A wall is the farthest surface in its direction:
// beyond its outline lie the image border, no depth, another wall or something in front of it; a large
// upright object (a laptop's lid) hides what is behind it. Outline pixels with nothing measured within
// reach are not counted.
float share_hiding_something(const std::vector<int>& face, int id, const cv::Mat& object_labels, const cv::Mat& points,
                             int reach) {
  constexpr float kFarther = 1.1f;
  const int width = object_labels.cols, height = object_labels.rows;
  int x0 = width, y0 = height, x1 = -1, y1 = -1;
  for (int i : face) {
    x0 = std::min(x0, i % width), x1 = std::max(x1, i % width);
    y0 = std::min(y0, i / width), y1 = std::max(y1, i / width);
  }
  x0 = std::max(0, x0 - 4 * reach), y0 = std::max(0, y0 - 4 * reach);
  x1 = std::min(width - 1, x1 + 4 * reach), y1 = std::min(height - 1, y1 + 4 * reach);
  const int* lab = object_labels.ptr<int>();
  const auto* pts = points.ptr<cv::Vec3f>();
  static constexpr int kSteps[4][2] = {{-1, 0}, {1, 0}, {0, -1}, {0, 1}};
  // A sample: every stride-th row and column (the same share at any resolution, a quarter of the work at VGA).
  const int stride = std::max(1, reach / 4);
  int seen = 0, hiding = 0;
  for (int y = y0; y <= y1; y += stride)
    for (int x = x0; x <= x1; x += stride) {
      const int i = y * width + x;
      if (lab[i] != id || !valid_point(pts[i])) continue;
      for (const auto& [dx, dy] : kSteps) {
        int xx = x + dx, yy = y + dy;
        if (xx < 0 || yy < 0 || xx >= width || yy >= height || lab[yy * width + xx] == id) continue;  // inside
        for (int k = 0; k < reach; ++k, xx += dx, yy += dy) {
          if (xx < 0 || yy < 0 || xx >= width || yy >= height) break;
          const int j = yy * width + xx;
          if (lab[j] == id || !valid_point(pts[j])) continue;
          ++seen;
          hiding += pts[j][2] > kFarther * pts[i][2];
          break;
        }
      }
    }
  return seen > 0 ? static_cast<float>(hiding) / static_cast<float>(seen) : 0.f;
}

}  // namespace

std::vector<Object> describe_objects(const cv::Mat& object_labels, const cv::Mat& points,
                                     const std::vector<int>& object_of_patch,
                                     const std::vector<float>& cut_cost, const Camera& camera) {
  if (object_labels.type() != CV_32S || points.type() != CV_32FC3 || object_labels.size() != points.size())
    throw Error("describe_objects: labels must be CV_32S and points CV_32FC3 of the same size");
  const std::vector<Run> runs = runs_of(object_labels);
  int count = 0;  // the largest label
  for (const Run& run : runs) count = std::max(count, run.object + 1);
  std::vector<Object> objects(static_cast<size_t>(count));
  describe_shapes(objects, std::vector<char>(objects.size(), 1), runs, points, camera);
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

void classify_objects(std::vector<Object>& objects, const std::vector<Patch>& patches, const cv::Mat& object_labels,
                      const cv::Mat& points, const Support& support, const Params::Support& params, int reach_px) {
  if (object_labels.type() != CV_32S || points.type() != CV_32FC3 || object_labels.size() != points.size())
    throw Error("classify_objects: labels must be CV_32S and points CV_32FC3 of the same size");
  const auto* pts = points.ptr<cv::Vec3f>();
  const int num_objects = static_cast<int>(objects.size());
  for (Object& object : objects)
    for (int p : object.patches)
      if (p >= 0 && p < static_cast<int>(patches.size()) && patches[static_cast<size_t>(p)].table) object.support = true;

  // Pixels of every other object, visited with a stride (bounded work per object).
  std::vector<Heights> heights(objects.size());
  std::vector<int> countdown(objects.size(), 0);
  const int samples_per_object = static_cast<int>(sample_budget(kSamplesPerObject, points));
  const auto visit = [&](int o, int i) {
    const Eigen::Vector3f q(pts[i][0], pts[i][1], pts[i][2]);
    const float d = support.plane.distance(q);
    Heights& h = heights[static_cast<size_t>(o)];
    ++h.samples;
    h.above_max += d > params.max_height;
    h.below += d < -plane_tolerance(params.plane_band, q.z());
    h.over_region += support.region.over(q);
    h.near_table += d < params.contact_distance;
  };
  for_each_run(object_labels, num_objects, [&](int o, int begin, int end) {
    if (objects[static_cast<size_t>(o)].support) return;
    const int stride = std::max(1, objects[static_cast<size_t>(o)].pixel_count / samples_per_object);
    int& wait = countdown[static_cast<size_t>(o)];
    if (count_valid(&pts[begin][0], end - begin) == end - begin) {  // the common case: every stride-th pixel
      int i = begin + wait;
      for (; i < end; i += stride) visit(o, i);
      wait = i - end;
      return;
    }
    for (int i = begin; i < end; ++i) {
      if (!valid_point(pts[i]) || wait-- > 0) continue;
      wait = stride - 1;
      visit(o, i);
    }
  });
  const Eigen::Vector3f up = support.plane.normal;
  // Beyond the paper: an upright object standing on the table (its foot within contact distance) in front
  // of something farther is an object, not a wall (a laptop's lid, a board); a wall above a ledge that
  // hides the room behind does not stand on the table.
  constexpr double kFootShare = 0.02;
  const auto stands_in_front = [&](const std::vector<int>& face, int id, const Heights& h) {
    return params.wall_hides_share > 0 && h.near_table >= kFootShare * h.samples &&
           share_hiding_something(face, id, object_labels, points, reach_px) >= params.wall_hides_share;
  };
  for (size_t o = 0; o < objects.size(); ++o) {
    Object& object = objects[o];
    const Heights& h = heights[o];
    if (object.support || h.samples == 0) continue;
    const double n = h.samples;
    // Far surfaces, the floor below the table, surfaces beside it.
    if (h.above_max > 0.5 * n || h.below > 0.5 * n || h.over_region < 0.3 * n) { object.background = true; continue; }
    // Walls: flat, standing roughly perpendicular to the table, and long along it (a tall box's face is
    // as flat and as upright, but narrow). The size first: it is known.
    if (object.box.extents(0) < params.wall_min_extent) continue;
    int largest = -1;
    for (int p : object.patches)
      if (largest < 0 || patches[static_cast<size_t>(p)].pixels.size() > patches[static_cast<size_t>(largest)].pixels.size()) largest = p;
    if (largest < 0) continue;
    const std::vector<int>& face = patches[static_cast<size_t>(largest)].pixels;
    Plane own;
    if (fit_plane(face, points, own) && mostly_within(face, points, own, params.plane_band, 0.9) &&
        std::abs(own.normal.dot(up)) < std::cos(60.0 * M_PI / 180.0) &&
        length_along(face, points, up.cross(own.normal).normalized()) >= params.wall_min_extent &&
        !stands_in_front(face, object.id, h))
      object.background = true;
  }
}

cv::Mat objects_only(const cv::Mat& object_labels, const std::vector<Object>& objects, bool keep_ids) {
  // New ids keep the order of the old ones, so the view is as stable as the labels it comes from;
  // tracked ids are kept as they are (object 3 stays object 3).
  int max_id = 0;
  for (const auto& o : objects) max_id = std::max(max_id, o.id);
  std::vector<int> new_id(static_cast<size_t>(max_id) + 1, 0);
  int next = 0;
  for (const auto& o : objects)
    if (!o.support && !o.background && o.id > 0) new_id[static_cast<size_t>(o.id)] = keep_ids ? o.id : ++next;
  cv::Mat out(object_labels.size(), CV_32S);
  const int last = static_cast<int>(new_id.size()) - 1;
  // Labels come in long runs (an object's row segments): one lookup and one fill per run.
  for (int y = 0; y < object_labels.rows; ++y) {
    const int* lab = object_labels.ptr<int>(y);
    int* view = out.ptr<int>(y);
    for (int begin = 0; begin < object_labels.cols;) {
      const int id = lab[begin], end = run_end(lab, begin, object_labels.cols);
      std::fill(view + begin, view + end, id > 0 && id <= last ? new_id[static_cast<size_t>(id)] : 0);
      begin = end;
    }
  }
  return out;
}

}  // namespace clutterseg
