// Paper j): remaining points. Pixels no patch took are grown into segments (8-connected, Euclidean
// distance between image neighbours), then each segment follows the paper's five rules:
//   1. no neighbouring face (missing depth around it)       -> a new object (none if tiny: noise)
//   2. one neighbouring face and tiny                       -> joins that face's object
//   3. one face: enclosed by it -> a new object, else joins it
//   4. several faces, all of one object                     -> joins that object
//   5. faces of several objects -> every pixel joins the object whose neighbouring face's plane it
//      fits best.
// Choices the paper leaves open:
// - "Neighbouring face" = a patch pixel 8-adjacent to the segment in the image.
// - "Enclosed" = the segment does not touch the image border or another remaining segment, and the
//   face holds at least half of its ring of neighbour pixels; the rest may be invalid pixels (the
//   shadow a Kinect casts beside every small object must not make it part of the table).
// - Beyond the paper: a segment grows across runs of up to Params::Remaining::gap_px pixels without depth
//   (a Kinect drops pixels all over a face seen at a grazing angle, which would leave it in specks, each
//   "tiny" and "without a face"), with grow_distance per pixel step: never across a depth jump.
// - Beyond the paper: a pixel on the table's plane is grown from a pixel clear of it, never into one
//   (Params::Remaining::apart_on_table): the table's edge band between two things' feet does not join them.
// - Beyond the paper: in rule 5 a segment that is a face of its own (its mean normal more than 30 deg from
//   every neighbouring face's local plane: the narrow side of a box seen edge-on) joins, whole, the face it
//   meets in a convex edge (n_s - n_f) . (c_s - c_f) > 0, as faces of one object meet, not the table or
//   the object it stands against (a concave crease).
// - Beyond the paper: a table face (TableHint) takes no pixel standing clear of the table's plane.
// - Beyond the paper: a segment whose one face is the table and that lies on the table around it (within
//   Params::Remaining::speck_band of its ring's height) is the table's, before rules 1-3: a bump of noise.
// - Beyond the paper: in rules 2-3 a segment seen behind its one face across depth jumps (most of its
//   contacts with it, Params::Remaining::occluded_jump) and nowhere within the jump of it in space is an
//   object that face hides, not a part of it. In rule 5 a face it is seen behind takes none of it.
// - Beyond the paper: the same for a face the segment stands before (jumps with the segment in front, nowhere
//   near in space, Params::Remaining::in_front) when the segment is concave to it; convex to it, it is the
//   face's rim (a bowl's outer wall before its inside).
// - Beyond the paper: in rule 5 a face resting on a top face of another object takes no pixel below that top's
//   plane (Params::Remaining::below_tops): a box's front under a can standing flush with it.
// - Beyond the paper: in rule 3 a segment whose one face holds less than Params::Remaining::min_contact_share of
//   its ring (a pan's wall without a patch that grazes a cup beside it) is an object of its own, not a part of it.
// - Beyond the paper: in rules 1-3 a segment that would be an object of its own (hidden behind its one face,
//   or cut off from every face by missing depth) joins the object on whose nearby faces' planes it lies, with
//   only nearer things between (the co-planarity cue f/g for a segment; Params::Remaining::hidden_coplanar_band).
// - Beyond the paper: two segments that became objects of their own behind one occluder (above), on either side of
//   it with only nearer things between them and on one plane or cylinder, are one object (Params::Remaining::
//   hidden_pairs): a small box behind an upright bar, seen on both sides of it, with no patch on either part.
// - Rule 5 is otherwise decided per pixel, not per segment: the remaining pixels between two objects are mostly
//   a bold edge band that belongs half to each, and boundaries decide the metrics. The plane of each
//   neighbouring face is a least-squares fit to that face's pixels near the segment (local, so a
//   curved face is modelled by its tangent plane where it touches the segment); least squares on all
//   nearby pixels is deterministic and does not need RANSAC's random draws.
#include "clutterseg/remaining.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <span>

#include "clutterseg/curvature.hpp"
#include "clutterseg/occlusion.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/support.hpp"

namespace clutterseg {

namespace {

// A segment is seen behind a face (Params::Remaining::occluded_jump) when its contacts with the face across a
// jump outnumber the continuous ones this many times.
constexpr int kHiddenRatio = 4;
// A hidden segment joins a face of another object when this share of its points lies on that face's plane;
// at most this many faces near it are fitted.
constexpr double kCoplanarShare = 0.8;
constexpr size_t kCoplanarCandidates = 6;
// Two hidden parts of one object (Params::Remaining::hidden_pairs): the line between their centroids passes
// behind nearer things for at least this share of its samples; pairs are looked at among at most this many parts.
constexpr double kPairHiddenShare = 0.25;
constexpr size_t kMaxHiddenPairs = 64;

struct Segment {
  size_t begin, end;  // its pixels in the list of all segments' pixels
  cv::Rect bbox;
};

// States of a pixel: no patch and no depth (the growing crosses it), a patch pixel, still to grow, grown into
// a segment, in the segment being looked at; plus a bit for the ring pixels of that segment.
constexpr uchar kNoDepth = 0, kFace = 1, kRemaining = 2, kGrown = 3, kInSegment = 4, kInRing = 0x80;
// A remaining pixel on the table's plane (Params::Remaining::apart_on_table), grown only from a pixel clear of the
// table or from another such pixel.
constexpr uchar kRemainingOnTable = 5;

// The first pixel at or after `from` still to grow (state.size() if none). memchr: the remaining pixels
// are few and scattered, and it scans many bytes per step.
int next_remaining(const std::vector<uchar>& state, int from, uchar which = kRemaining) {
  const auto* found = static_cast<const uchar*>(std::memchr(state.data() + from, which, state.size() - static_cast<size_t>(from)));
  return static_cast<int>(found ? found - state.data() : static_cast<std::ptrdiff_t>(state.size()));
}

// Object id of every pixel (obj) and the state of every pixel: kFace, kRemaining (no patch but a valid
// point) or kNoDepth. Returns their count; *max_label = the largest label seen. Labels come
// in long runs (a patch's row segments): one lookup and one fill per run, and the depth is read only in
// runs of label 0 (edge bands and holes: a small share of the image).
int mark_remaining(const int* __restrict lab, const float* __restrict xyz, const int* __restrict object_of_label,
                   int total, int num_patches, int* __restrict obj, uchar* __restrict state, int* __restrict max_label) {
  int count = 0, largest = 0;
  for (int begin = 0; begin < total;) {
    const int l = lab[begin], end = run_end(lab, begin, total);
    largest = std::max(largest, l);
    std::fill(obj + begin, obj + end, object_of_label[std::clamp(l, 0, num_patches)]);  // out of range: the caller
    if (l == 0)
      for (int i = begin; i < end; ++i) {
        const bool remaining = valid_depth(xyz[3 * i + 2]);
        state[i] = remaining ? kRemaining : kNoDepth;
        count += remaining;
      }
    else
      std::memset(state + begin, kFace, static_cast<size_t>(end - begin));
    begin = end;
  }
  *max_label = largest;
  return count;
}

constexpr int kDx[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
constexpr int kDy[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
// A face's normals and a segment's differ by more than this when the segment is a face of its own.
const float kOwnFaceCos = static_cast<float>(std::cos(30.0 * M_PI / 180.0));
// Convexity (contact.hpp) above which a face of its own joins a neighbouring face.
constexpr float kConvex = 0.1f;
// A face facing up within this of the table's normal is a top face (as convexity.top_angle_deg).
const float kTopCos = static_cast<float>(std::cos(20.0 * M_PI / 180.0));

// A surface's mean normal and centroid (over its pixels with a normal); false when there are fewer than three
// or their normals disagree too much to average (a curved segment).
struct MeanNormal {
  Eigen::Vector3f normal, centroid;
};
std::optional<MeanNormal> mean_normal(std::span<const int> pixels, const NormalPlanes& normals, const cv::Vec3f* pts) {
  Eigen::Vector3f normal = Eigen::Vector3f::Zero(), centroid = Eigen::Vector3f::Zero();
  int n = 0;
  for (int i : pixels) {
    const Eigen::Vector3f ni(normals[0].ptr<float>()[i], normals[1].ptr<float>()[i], normals[2].ptr<float>()[i]);
    if (ni.squaredNorm() < 0.5f) continue;  // no normal here
    normal += ni;
    centroid += Eigen::Vector3f(pts[i][0], pts[i][1], pts[i][2]);
    ++n;
  }
  if (n < 3 || !(normal.norm() > 0.5f * static_cast<float>(n))) return std::nullopt;
  return MeanNormal{normal.normalized(), centroid / static_cast<float>(n)};
}

// Convexity (n_s - n_f) . (c_s - c_f) / |c_s - c_f| of a segment against a face's local plane (contact.hpp);
// NaN when the centroids coincide.
float convexity_to(const MeanNormal& segment, const Eigen::Vector3f& face_normal, const Eigen::Vector3f& face_centroid) {
  const Eigen::Vector3f d = segment.centroid - face_centroid;
  if (!(d.norm() > 1e-4f)) return std::numeric_limits<float>::quiet_NaN();
  return (segment.normal - face_normal).dot(d) / d.norm();
}

// Least-squares plane of the pixels labelled `patch` in `window` (visited with a stride so that at most
// about kMaxVisits pixels are read). Returns false when they are too few or collinear.
constexpr int kMaxVisits = 4000;
bool fit_local_plane(const cv::Mat& labels, const cv::Mat& points, int patch, cv::Rect window, Plane& plane,
                     Eigen::Vector3f& centroid) {
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(window.area()) / kMaxVisits))));
  PlaneFit fit;
  for (int y = window.y; y < window.y + window.height; y += stride) {
    const int* lab = labels.ptr<int>(y);
    const auto* pts = points.ptr<cv::Vec3f>(y);
    for (int x = window.x; x < window.x + window.width; x += stride)
      if (lab[x] == patch && valid_point(pts[x])) fit.add({pts[x][0], pts[x][1], pts[x][2]});
  }
  if (!fit.plane(plane)) return false;
  centroid = fit.mean();
  return true;
}

// `box` grown by `margin` pixels on every side, within the image.
cv::Rect grown(const cv::Rect& box, int margin, const cv::Mat& image) {
  return cv::Rect(box.x - margin, box.y - margin, box.width + 2 * margin, box.height + 2 * margin) &
         cv::Rect(0, 0, image.cols, image.rows);
}

// The margin of the window around a segment's box in which a face's local plane is fitted first.
int first_margin(const cv::Rect& bbox) { return std::max(8, std::max(bbox.width, bbox.height) / 2); }

// Whether some point of `segment` lies within `distance` (3D) of a point of `patch` in the segment's box
// grown by its size: a surface that meets the face in space (a cylinder's top its side), not only in the
// image (an object behind an occluder). Both sides are sampled (at most kMaxVisits face points).
bool meets_in_space(std::span<const int> segment, const cv::Rect& bbox, const cv::Mat& labels, const cv::Mat& points,
                    int patch, float distance) {
  const cv::Rect window = grown(bbox, std::max(bbox.width, bbox.height), labels);
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(window.area()) / kMaxVisits))));
  std::vector<Eigen::Vector3f> face;
  for (int y = window.y; y < window.y + window.height; y += stride) {
    const int* lab = labels.ptr<int>(y);
    const auto* pts = points.ptr<cv::Vec3f>(y);
    for (int x = window.x; x < window.x + window.width; x += stride)
      if (lab[x] == patch && valid_point(pts[x])) face.emplace_back(pts[x][0], pts[x][1], pts[x][2]);
  }
  // By depth: a segment point looks only at the face points in its slab of depths (none, when hidden).
  std::sort(face.begin(), face.end(), [](const Eigen::Vector3f& a, const Eigen::Vector3f& b) { return a.z() < b.z(); });
  const auto* pts = points.ptr<cv::Vec3f>();
  const size_t step = std::max<size_t>(1, segment.size() / 200);
  const float d2 = distance * distance;
  for (size_t k = 0; k < segment.size(); k += step) {
    const cv::Vec3f& q = pts[segment[k]];
    const Eigen::Vector3f p(q[0], q[1], q[2]);
    auto f = std::lower_bound(face.begin(), face.end(), p.z() - distance,
                              [](const Eigen::Vector3f& a, float z) { return a.z() < z; });
    for (; f != face.end() && f->z() <= p.z() + distance; ++f)
      if ((*f - p).squaredNorm() < d2) return true;
  }
  return false;
}

// Whether the points of `patch` near `bbox` (the window of its local plane, a stride: at most about kMaxVisits read) rest on
// `top`: at least 95 % of them above its plane or less than `band` (plane_tolerance) below it, their mean above
// it by more than that, and at least 5 % of them within kRestingHeight of it (touching it: not a surface far
// behind that only lies above the top's plane extended); false when fewer than 10.
constexpr float kRestingHeight = 0.02f;
bool rests_on(const cv::Mat& labels, const cv::Mat& points, int patch, const cv::Rect& bbox, const Plane& top, double band) {
  const cv::Rect window = grown(bbox, first_margin(bbox), labels);
  const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(window.area()) / kMaxVisits))));
  int n = 0, below = 0, low = 0;
  double height = 0;
  for (int y = window.y; y < window.y + window.height; y += stride) {
    const int* lab = labels.ptr<int>(y);
    const auto* pts = points.ptr<cv::Vec3f>(y);
    for (int x = window.x; x < window.x + window.width; x += stride) {
      if (lab[x] != patch || !valid_point(pts[x])) continue;
      const float h = top.distance({pts[x][0], pts[x][1], pts[x][2]});
      below += h < -plane_tolerance(band, pts[x][2]);
      low += h < kRestingHeight;
      height += h;
      ++n;
    }
  }
  return n >= 10 && below <= n / 20 && 20 * low >= n && height / n > plane_tolerance(band, 1.f);
}

// Plane of `patch` near `bbox`: the window grows until the fit is possible (bounded: whole image).
bool fit_plane_near(const cv::Mat& labels, const cv::Mat& points, int patch, const cv::Rect& bbox, Plane& plane,
                    Eigen::Vector3f& centroid) {
  const cv::Rect image(0, 0, labels.cols, labels.rows);
  for (int attempt = 0, margin = first_margin(bbox); attempt < 8; ++attempt, margin *= 2) {
    const cv::Rect window = grown(bbox, margin, labels);
    if (fit_local_plane(labels, points, patch, window, plane, centroid)) return true;
    if (window == image) break;
  }
  return false;
}

// Median height above `plane` of at most ~256 of `pixels` (a stride: a large segment would cost a pass of its
// own) that `take` accepts; NaN if none.
template <typename Take>
float median_height(std::span<const int> pixels, const cv::Vec3f* pts, const Plane& plane, Take take) {
  std::vector<float> heights;
  const size_t stride = std::max<size_t>(1, pixels.size() / 256);
  for (size_t k = 0; k < pixels.size(); k += stride)
    if (const int i = pixels[k]; take(i) && valid_point(pts[i])) heights.push_back(plane.distance({pts[i][0], pts[i][1], pts[i][2]}));
  if (heights.empty()) return std::numeric_limits<float>::quiet_NaN();
  std::nth_element(heights.begin(), heights.begin() + static_cast<std::ptrdiff_t>(heights.size() / 2), heights.end());
  return heights[heights.size() / 2];
}

// Beyond the paper (Params::Remaining::speck_band): whether a segment lies on the table around it, its median
// height above the table's plane within `band` of the median of its ring's pixels on table face `label`. A
// stereo camera's table lies a few mm off its fitted plane here and there, with bumps of noise on it.
bool lies_on_table_around(std::span<const int> seg_pixels, const std::vector<int>& ring, int label, const int* lab,
                          const cv::Vec3f* pts, const TableHint& table, double band) {
  const float ring_height = median_height(ring, pts, table.plane, [&](int j) { return lab[j] == label; });
  const float seg_height = median_height(seg_pixels, pts, table.plane, [](int) { return true; });
  if (!std::isfinite(ring_height) || !std::isfinite(seg_height)) return false;
  const float z = pts[seg_pixels[seg_pixels.size() / 2]][2];
  return std::abs(seg_height - ring_height) <= plane_tolerance(band, valid_depth(z) ? z : 1.f);
}

}  // namespace

cv::Mat assign_remaining(const cv::Mat& assigned_labels, const std::vector<int>& object_of_patch,
                         int num_objects, const cv::Mat& points, const NormalPlanes& normals,
                         const Params::Remaining& params, int tiny_px, const std::optional<TableHint>& table,
                         const OcclusionCheck* occlusion, int gap_px) {
  if (assigned_labels.type() != CV_32S || points.type() != CV_32FC3 || assigned_labels.size() != points.size())
    throw Error("assign_remaining: labels must be CV_32S and points CV_32FC3 of the same size");
  const bool have_normals = !normals[0].empty();
  if (have_normals && (normals[0].size() != points.size() || normals[1].size() != points.size() ||
                       normals[2].size() != points.size()))
    throw Error("assign_remaining: normals must have the size of the points");
  if (table && table->table_patch.size() != object_of_patch.size())
    throw Error("assign_remaining: the table hint must have one flag per patch");
  const int width = assigned_labels.cols, height = assigned_labels.rows;
  const int total = width * height;
  const int* lab = assigned_labels.ptr<int>();
  const auto* pts = points.ptr<cv::Vec3f>();
  const int num_patches = static_cast<int>(object_of_patch.size());
  for (int o : object_of_patch)
    if (o < 0 || o >= num_objects) throw Error("assign_remaining: object index out of range");

  // Object id of every patch label (index 0: no patch).
  std::vector<int> object_of_label(static_cast<size_t>(num_patches) + 1, 0);
  for (int p = 0; p < num_patches; ++p) object_of_label[static_cast<size_t>(p) + 1] = object_of_patch[static_cast<size_t>(p)] + 1;
  cv::Mat objects(assigned_labels.size(), CV_32S);
  int* obj = objects.ptr<int>();
  // Every pixel's state is marked once, so the growing below reads one byte per pixel.
  std::vector<uchar> state(static_cast<size_t>(total), 0);
  int max_label = 0;
  const auto num_remaining = static_cast<size_t>(
      mark_remaining(lab, &pts[0][0], object_of_label.data(), total, num_patches, obj, state.data(), &max_label));
  if (max_label > num_patches) throw Error("assign_remaining: patch label out of range");

  // Region growing of the remaining pixels. The pixels of all segments are stored one after another
  // (Segment::begin, end).
  std::vector<Segment> segments;
  const float grow2 = static_cast<float>(params.grow_distance * params.grow_distance);
  std::vector<int> pixels;
  pixels.reserve(num_remaining);
  int offset[8];  // of the 8 neighbours, as index differences
  for (int k = 0; k < 8; ++k) offset[k] = kDy[k] * width + kDx[k];
  const int reach = 1 + std::max(0, gap_px);  // steps along a direction: the neighbour, then across the gap
  std::vector<float> limit2(static_cast<size_t>(reach) + 1);  // grow_distance per pixel step
  for (int s = 1; s <= reach; ++s) limit2[static_cast<size_t>(s)] = grow2 * static_cast<float>(s * s);
  // Beyond the paper: the remaining pixels on the table's plane are grown from the others but never grow into them,
  // then the rest among themselves: the table's edge band between two objects' feet does not join the two.
  std::vector<uchar> grown_on_table;  // per entry of `pixels`: it was on the table's plane
  const bool apart_on_table = table && params.apart_on_table;
  if (apart_on_table) {
    grown_on_table.reserve(num_remaining);
    for (int i = next_remaining(state, 0); i < total; i = next_remaining(state, i + 1))
      if (std::abs(table->plane.distance({pts[i][0], pts[i][1], pts[i][2]})) <= plane_tolerance(table->pixel_band, pts[i][2]))
        state[static_cast<size_t>(i)] = kRemainingOnTable;
  }
  const auto grow = [&](int pixel) {
    if (apart_on_table) grown_on_table.push_back(state[static_cast<size_t>(pixel)] == kRemainingOnTable);
    state[static_cast<size_t>(pixel)] = kGrown;
    pixels.push_back(pixel);
  };
  for (const uchar seeds : {kRemaining, kRemainingOnTable})
  for (int seed_px = next_remaining(state, 0, seeds); seed_px < total; seed_px = next_remaining(state, seed_px + 1, seeds)) {
    const size_t begin = pixels.size();
    grow(seed_px);
    int x0 = width, y0 = height, x1 = -1, y1 = -1;
    for (size_t head = begin; head < pixels.size(); ++head) {  // every pixel enters once: bounded
      const int i = pixels[head];
      const int x = i % width, y = i / width;
      const bool from_table = apart_on_table && grown_on_table[head];
      x0 = std::min(x0, x); x1 = std::max(x1, x); y0 = std::min(y0, y); y1 = std::max(y1, y);
      // Along each of the 8 directions: the neighbour, and beyond it while the pixels passed have no depth
      // (at most gap_px of them). Pixels `reach` steps inside the image need no border test (most of them).
      const bool inside = x >= reach && y >= reach && x + reach < width && y + reach < height;
      for (int k = 0; k < 8; ++k)
        for (int s = 1, j = i + offset[k]; s <= reach; ++s, j += offset[k]) {
          if (!inside) {
            const int xx = x + s * kDx[k], yy = y + s * kDy[k];
            if (xx < 0 || yy < 0 || xx >= width || yy >= height) break;
          }
          const uchar here = state[static_cast<size_t>(j)];
          if ((here == kRemaining && !from_table) || here == kRemainingOnTable)
            if (distance2(pts[i], pts[j]) < limit2[static_cast<size_t>(s)]) grow(j);
          if (here != kNoDepth) break;  // only pixels without depth (and no patch) are crossed
        }
    }
    segments.push_back({begin, pixels.size(), cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1)});
  }

  int next_object = num_objects;
  std::vector<int> ring;                      // per segment: its ring pixels
  // A neighbouring face of a segment: its ring pixels on the face, and (for a non-table face) how many of
  // them lie across a depth jump with the segment behind, across one with the segment in front, or on neither.
  struct Face {
    int label, ring = 0, behind = 0, front = 0, touching = 0;
    bool hides() const { return behind > kHiddenRatio * touching; }           // contacts mostly across a jump
    bool apart() const { return behind + front > kHiddenRatio * touching; }  // either way round
  };
  std::vector<Face> faces;  // per segment, sorted by label
  struct FacePlane {
    Plane plane;
    Eigen::Vector3f centroid;
    int object_id;
    bool table;
    int label;
  };
  std::vector<FacePlane> planes;  // per segment in rule 5
  std::vector<std::pair<size_t, size_t>> resting;  // per segment in rule 5: (face, top face it rests on)
  const float occluded_jump2 = static_cast<float>(params.occluded_jump * params.occluded_jump);
  const auto is_table = [&](int patch_label) { return table && table->table_patch[static_cast<size_t>(patch_label - 1)]; };
  // A point standing clear of the table's plane: no table face takes it.
  const auto clear_of_table = [&](const cv::Vec3f& q) {
    return table && table->plane.distance({q[0], q[1], q[2]}) > plane_tolerance(table->pixel_band, q[2]);
  };
  const auto on_table_around = [&](std::span<const int> seg_pixels, const std::vector<int>& ring, int label) {
    return table && params.speck_band > 0 && lies_on_table_around(seg_pixels, ring, label, lab, pts, *table, params.speck_band);
  };
  // Beyond the paper: the object (id), not the occluder's (`occluder`), whose faces near a segment cut off
  // by an occluder hold at least kCoplanarShare of the segment's points on their local planes
  // (plane_tolerance(hidden_coplanar_band, z); a segment may hold a box's top and front, so a point counts
  // when it lies on any face of that object), with nothing behind the line between the segment and each
  // such face (co-planarity's occlusion check, g); 0 if none. The faces looked for are those in the
  // segment's box grown by twice its size on every side (an occluder twice as wide as the segment), read
  // with a stride (at most about kMaxVisits pixels); at most kCoplanarCandidates of them are fitted.
  // A point on a face's plane or on the cylinder through it, within hidden_coplanar_band (times z^2).
  const auto on_surface = [&](const cv::Vec3f& q, const Plane& plane, const std::optional<Cylinder>& cylinder) {
    const double band = plane_tolerance(params.hidden_coplanar_band, q[2]);
    return std::abs(plane.distance({q[0], q[1], q[2]})) <= band ||
           (cylinder && cylinder->distance(Eigen::Vector3d(q[0], q[1], q[2])) <= band);
  };
  // The mean point of a segment's pixels (all have depth: they were grown).
  const auto centroid_of_pixels = [&](std::span<const int> seg_pixels) {
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    for (int i : seg_pixels) sum += Eigen::Vector3f(pts[i][0], pts[i][1], pts[i][2]);
    return Eigen::Vector3f(sum / static_cast<float>(seg_pixels.size()));
  };
  std::vector<uchar> on_face;  // per segment pixel: on a face of the object looked at
  std::vector<int> face_pixels;  // a face's pixels in the window, for a cylinder through them
  const auto coplanar_object = [&](std::span<const int> seg_pixels, const cv::Rect& bbox, int occluder) {
    const auto object_of = [&](int patch_label) { return object_of_patch[static_cast<size_t>(patch_label - 1)] + 1; };
    if (!occlusion) return 0;
    const Eigen::Vector3f own_centroid = centroid_of_pixels(seg_pixels);
    const cv::Rect window = grown(bbox, 2 * std::max(bbox.width, bbox.height), assigned_labels);
    const int stride = std::max(1, static_cast<int>(std::ceil(std::sqrt(double(window.area()) / kMaxVisits))));
    std::vector<std::pair<int, int>> seen;  // (visits, patch label)
    for (int y = window.y; y < window.y + window.height; y += stride)
      for (int x = window.x; x < window.x + window.width; x += stride) {
        const int l = lab[y * width + x];
        if (l <= 0 || is_table(l) || object_of(l) == occluder) continue;
        auto it = std::find_if(seen.begin(), seen.end(), [&](const auto& v) { return v.second == l; });
        if (it == seen.end()) seen.emplace_back(1, l); else ++it->first;
      }
    std::sort(seen.begin(), seen.end(), [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
    if (seen.size() > kCoplanarCandidates) seen.resize(kCoplanarCandidates);
    // The faces that pass the occlusion check, with their planes (and, with params.hidden_curved, a cylinder
    // through their pixels in the window), grouped by object below.
    struct FaceNear {
      int object;
      Plane plane;
      std::optional<Cylinder> cylinder;
    };
    std::vector<FaceNear> faces_near;
    for (const auto& [visits, l] : seen) {
      Plane plane;
      Eigen::Vector3f centroid;
      if (!fit_plane_near(assigned_labels, points, l, bbox, plane, centroid)) continue;
      if (behind_fraction(own_centroid, centroid, points, occlusion->camera, occlusion->tolerance) > occlusion->max_fraction)
        continue;  // background between them: not seen through a nearer thing
      std::optional<Cylinder> cylinder;
      if (params.hidden_curved && have_normals) {
        face_pixels.clear();
        for (int y = window.y; y < window.y + window.height; y += stride)
          for (int x = window.x; x < window.x + window.width; x += stride)
            if (lab[y * width + x] == l) face_pixels.push_back(y * width + x);
        cylinder = fit_cylinder(face_pixels, points, normals);
      }
      faces_near.push_back({object_of(l), plane, cylinder});
    }
    int best_object = 0;
    double best_share = kCoplanarShare;
    for (size_t f = 0; f < faces_near.size(); ++f) {
      const int object = faces_near[f].object;
      if (std::any_of(faces_near.begin(), faces_near.begin() + static_cast<std::ptrdiff_t>(f), [&](const auto& g) { return g.object == object; }))
        continue;  // this object was counted with its first face
      on_face.assign(seg_pixels.size(), 0);
      for (size_t g = f; g < faces_near.size(); ++g) {
        if (faces_near[g].object != object) continue;
        for (size_t k = 0; k < seg_pixels.size(); ++k)
          on_face[k] |= on_surface(pts[seg_pixels[k]], faces_near[g].plane, faces_near[g].cylinder);
      }
      const double share = static_cast<double>(std::count(on_face.begin(), on_face.end(), 1)) / static_cast<double>(seg_pixels.size());
      if (share > best_share) { best_share = share; best_object = object; }
    }
    return best_object;
  };
  // Segments made objects of their own behind an occluder (0: cut off by missing depth), with no far part found.
  struct HiddenAlone {
    size_t segment;
    int occluder, object;
  };
  std::vector<HiddenAlone> hidden_alone;
  for (size_t s = 0; s < segments.size(); ++s) {
    const Segment& seg = segments[s];
    const std::span<const int> seg_pixels(pixels.data() + seg.begin, seg.end - seg.begin);
    // The ring: pixels 8-adjacent to the segment, each counted once (marked in `state` while the
    // segment is looked at, then unmarked: the work stays proportional to the segment).
    bool touches_border = false;
    int other_segment = 0, invalid = 0;
    faces.clear();
    ring.clear();
    for (int i : seg_pixels) state[static_cast<size_t>(i)] = kInSegment;
    for (int i : seg_pixels) {
      const int x = i % width, y = i / width;
      const bool inside = x >= 1 && y >= 1 && x + 1 < width && y + 1 < height;  // no border test needed
      for (int k = 0; k < 8; ++k) {
        int j = i + offset[k];
        if (!inside) {
          const int xx = x + kDx[k], yy = y + kDy[k];
          if (xx < 0 || yy < 0 || xx >= width || yy >= height) { touches_border = true; continue; }
          j = yy * width + xx;
        }
        // In the segment or in the ring already (kInSegment has no ring bit and is the only state above
        // kGrown without it): one test for both.
        if (state[static_cast<size_t>(j)] >= kInSegment) continue;
        state[static_cast<size_t>(j)] |= kInRing;
        ring.push_back(j);
        if (lab[j] > 0) {
          auto face = std::find_if(faces.begin(), faces.end(), [&](const Face& f) { return f.label == lab[j]; });
          if (face == faces.end()) face = faces.insert(faces.end(), Face{lab[j]});
          ++face->ring;
          if (occluded_jump2 > 0 && !is_table(lab[j])) {
            if (distance2(pts[i], pts[j]) <= occluded_jump2) ++face->touching;
            else if (pts[i][2] > pts[j][2]) ++face->behind;
            else ++face->front;
          }
        } else if (state[static_cast<size_t>(j)] == (kGrown | kInRing)) {
          ++other_segment;
        } else {
          ++invalid;
        }
      }
    }
    for (int i : seg_pixels) state[static_cast<size_t>(i)] = kGrown;
    for (int j : ring) state[static_cast<size_t>(j)] &= static_cast<uchar>(~kInRing);
    std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.label < b.label; });  // scan order free
    // The table face of a segment that has no other face and is no tiny speck (which joins it or is noise), asked
    // only where the rules below would not give the segment to the table anyway: it lies on the table around it.
    const int table_face = faces.size() == 1 && is_table(faces[0].label) && static_cast<int>(seg_pixels.size()) >= tiny_px
                               ? faces[0].label : 0;
    bool speck = false;
    if (table && std::any_of(faces.begin(), faces.end(), [&](const Face& f) { return is_table(f.label); })) {
      // A segment mostly clear of the table is not the table's, whatever else it touches.
      int clear = 0;
      for (int i : seg_pixels) clear += clear_of_table(pts[i]);
      if (2 * clear > static_cast<int>(seg_pixels.size())) {
        speck = table_face > 0 && on_table_around(seg_pixels, ring, table_face);
        if (!speck) std::erase_if(faces, [&](const Face& f) { return is_table(f.label); });
      }
    }
    auto set_all = [&](int object_id) { for (int i : seg_pixels) obj[i] = object_id; };
    // Seen behind the face (most contacts across a jump) and meeting it nowhere in space: hidden by it.
    const auto meets = [&](const Face& f) {
      return meets_in_space(seg_pixels, seg.bbox, assigned_labels, points, f.label, static_cast<float>(params.occluded_jump));
    };
    const auto hidden_by = [&](const Face& f) { return f.hides() && !meets(f); };
    // The segment's mean normal, computed when first asked for.
    std::optional<MeanNormal> own_normal;
    bool own_normal_known = false;
    const auto segment_normal = [&]() -> const std::optional<MeanNormal>& {
      if (!own_normal_known && have_normals) own_normal = mean_normal(seg_pixels, normals, pts);
      own_normal_known = true;
      return own_normal;
    };
    // Seen in front of the face across jumps, meeting it nowhere in space and not convex to it: a thing standing
    // before the face (a box's steep face before a cylinder), not its rim (a bowl's wall before its inside is
    // convex to it, as the paper's open objects).
    const auto in_front_of = [&](const Face& f) {
      if (!params.in_front || !f.apart() || f.hides() || !segment_normal()) return false;
      Plane plane;
      Eigen::Vector3f centroid;
      return fit_plane_near(assigned_labels, points, f.label, seg.bbox, plane, centroid) &&
             convexity_to(*segment_normal(), plane.normal, centroid) < 0.f && !meets(f);
    };
    auto object_of = [&](int patch_label) { return object_of_patch[static_cast<size_t>(patch_label - 1)] + 1; };
    // A hidden segment (not tiny): the far part of an object the face cuts in two (co-planarity, f/g), or an
    // object of its own.
    const auto hidden_object = [&](const Face& occluder) {
      const int coplanar = params.hidden_coplanar_band > 0 ? coplanar_object(seg_pixels, seg.bbox, object_of(occluder.label)) : 0;
      if (coplanar > 0) return coplanar;
      hidden_alone.push_back({s, object_of(occluder.label), next_object + 1});
      return ++next_object;
    };

    if (faces.empty()) {                                              // rule 1
      // A tiny segment alone is sensor noise (stereo sensors leave thousands of them), not an object.
      // Beyond the paper: cut off by missing depth (an occluder's shadow), it may be the far part of an object.
      if (static_cast<int>(seg_pixels.size()) >= tiny_px) {
        const int coplanar = params.hidden_coplanar_band > 0 ? coplanar_object(seg_pixels, seg.bbox, 0) : 0;
        if (coplanar == 0) hidden_alone.push_back({s, 0, next_object + 1});
        set_all(coplanar > 0 ? coplanar : ++next_object);
      }
      continue;
    }
    if (faces.size() == 1) {
      const bool tiny = static_cast<int>(seg_pixels.size()) < tiny_px;          // rule 2
      const Face& face = faces[0];
      const bool enclosed = !touches_border && other_segment == 0 && face.ring >= invalid;  // rule 3
      // Beyond the paper: touching its one face in a pixel or two of its ring, the segment is no part of it.
      const bool grazing = face.ring < params.min_contact_share * static_cast<double>(ring.size());
      // Beyond the paper: on the table around it, enclosed or grazing, a bump of noise is the table's.
      if (!tiny && (enclosed || grazing) && !speck && face.label == table_face)
        speck = on_table_around(seg_pixels, ring, table_face);
      // Beyond the paper: seen behind its one face (most of their contacts across a depth jump) and nowhere
      // near it in space, the segment is an object that face hides, not a part of it.
      if (!tiny && (hidden_by(face) || in_front_of(face))) set_all(hidden_object(face));
      else set_all(!tiny && (enclosed || grazing) && !speck ? ++next_object : object_of(face.label));
      continue;
    }
    // Beyond the paper: a face the segment is seen behind (most of their contacts across a jump) hides it and
    // takes none of it; hidden behind every face, it is an object of its own (or of the far part's, as above).
    const Face longest = *std::max_element(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.ring < b.ring; });
    std::erase_if(faces, [&](const Face& f) { return f.hides() || in_front_of(f); });
    if (faces.empty()) {
      set_all(static_cast<int>(seg_pixels.size()) < tiny_px ? object_of(longest.label) : hidden_object(longest));
      continue;
    }
    const int first_object = object_of(faces[0].label);
    if (std::all_of(faces.begin(), faces.end(), [&](const Face& f) { return object_of(f.label) == first_object; })) {
      set_all(first_object);                                          // rule 4
      continue;
    }
    // Rule 5: the local plane of every neighbouring face.
    planes.clear();
    for (const Face& f : faces) {
      Plane plane;
      Eigen::Vector3f centroid;
      if (fit_plane_near(assigned_labels, points, f.label, seg.bbox, plane, centroid))
        planes.push_back({plane, centroid, object_of(f.label), is_table(f.label), f.label});
    }
    if (planes.empty()) {  // only degenerate faces: the face with the longest contact takes it
      const auto best = std::max_element(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.ring < b.ring; });
      set_all(object_of(best->label));
      continue;
    }
    // A face of its own joins the face it meets in the most convex edge.
    if (const auto& own = segment_normal()) {
      const bool own_face = std::all_of(planes.begin(), planes.end(), [&](const FacePlane& f) {
        return std::abs(own->normal.dot(f.plane.normal)) < kOwnFaceCos;
      });
      if (own_face) {
        const FacePlane* best = nullptr;
        float best_convexity = kConvex;
        for (const FacePlane& f : planes) {
          const float c = f.table ? std::numeric_limits<float>::quiet_NaN() : convexity_to(*own, f.plane.normal, f.centroid);
          if (c > best_convexity) { best_convexity = c; best = &f; }
        }
        if (best) {
          set_all(best->object_id);
          continue;
        }
      }
    }
    // Beyond the paper: a face resting on a top face of another object (a neighbouring face facing up, within
    // 20 deg of the table's normal) takes no pixel below that top's plane: a box's front below a can standing
    // flush with it lies on the can's tangent plane, but not under the box's top.
    resting.clear();
    if (table && params.below_tops)
      for (size_t t = 0; t < planes.size(); ++t) {
        if (planes[t].table || planes[t].plane.normal.dot(table->plane.normal) < kTopCos) continue;
        for (size_t f = 0; f < planes.size(); ++f)
          if (!planes[f].table && planes[f].object_id != planes[t].object_id &&
              rests_on(assigned_labels, points, planes[f].label, seg.bbox, planes[t].plane, table->pixel_band))
            resting.emplace_back(f, t);
      }
    const auto under_its_top = [&](size_t f, const Eigen::Vector3f& q) {
      return std::any_of(resting.begin(), resting.end(), [&](const auto& r) {
        return r.first == f && planes[r.second].plane.distance(q) < -plane_tolerance(table->pixel_band, q.z());
      });
    };
    // Per pixel, the neighbouring face whose local plane fits best (no table face for a pixel clear of it).
    for (int i : seg_pixels) {
      const Eigen::Vector3f q(pts[i][0], pts[i][1], pts[i][2]);
      const bool clear = clear_of_table(pts[i]);
      float best = std::numeric_limits<float>::infinity();
      for (size_t f = 0; f < planes.size(); ++f) {
        const float d = std::abs(planes[f].plane.distance(q));
        if (d < best && !(clear && planes[f].table) && !under_its_top(f, q)) { best = d; obj[i] = planes[f].object_id; }
      }
    }
  }
  // Beyond the paper (Params::Remaining::hidden_pairs): two such segments on either side of one occluder, with only
  // nearer things between them and one surface through both (a plane or a cylinder, hidden_coplanar_band), are the
  // two visible parts of one object.
  if (params.hidden_pairs && occlusion && params.hidden_coplanar_band > 0 && hidden_alone.size() >= 2 &&
      hidden_alone.size() <= kMaxHiddenPairs) {
    std::vector<int> root(hidden_alone.size());
    std::iota(root.begin(), root.end(), 0);
    const auto find = [&](int a) { return find_root(root, a); };
    std::vector<std::optional<Eigen::Vector3f>> centroids(hidden_alone.size());  // computed when first asked for
    const auto centroid_of = [&](size_t h) {
      if (!centroids[h]) {
        const Segment& seg = segments[hidden_alone[h].segment];
        centroids[h] = centroid_of_pixels(std::span<const int>(pixels.data() + seg.begin, seg.end - seg.begin));
      }
      return *centroids[h];
    };
    std::vector<int> both;
    for (size_t a = 0; a < hidden_alone.size(); ++a)
      for (size_t b = a + 1; b < hidden_alone.size(); ++b) {
        const HiddenAlone &ha = hidden_alone[a], &hb = hidden_alone[b];
        if (ha.occluder != hb.occluder && ha.occluder != 0 && hb.occluder != 0) continue;
        const Segment &sa = segments[ha.segment], &sb = segments[hb.segment];
        const int reach = 2 * std::max({sa.bbox.width, sa.bbox.height, sb.bbox.width, sb.bbox.height});  // as coplanar_object
        if ((grown(sa.bbox, reach, assigned_labels) & sb.bbox).area() == 0) continue;
        const GapView gap = view_gap(centroid_of(a), centroid_of(b), points, occlusion->camera, occlusion->tolerance);
        if (gap.behind > occlusion->max_fraction || gap.in_front < kPairHiddenShare) continue;
        both.assign(pixels.begin() + static_cast<std::ptrdiff_t>(sa.begin), pixels.begin() + static_cast<std::ptrdiff_t>(sa.end));
        both.insert(both.end(), pixels.begin() + static_cast<std::ptrdiff_t>(sb.begin), pixels.begin() + static_cast<std::ptrdiff_t>(sb.end));
        // The same test as for a face near a segment (coplanar_object): on the plane or the cylinder through both.
        Plane plane;
        if (!fit_plane(both, points, plane)) continue;
        const std::optional<Cylinder> cylinder = params.hidden_curved && have_normals ? fit_cylinder(both, points, normals) : std::nullopt;
        const auto on = std::count_if(both.begin(), both.end(), [&](int i) { return on_surface(pts[i], plane, cylinder); });
        if (static_cast<double>(on) >= kCoplanarShare * static_cast<double>(both.size())) root[static_cast<size_t>(find(static_cast<int>(b)))] = find(static_cast<int>(a));
      }
    // Relabel the joined parts with their first part's object, and number the new objects 1.. again without gaps.
    std::vector<int> renamed(static_cast<size_t>(next_object) + 1);
    for (int o = 0; o <= next_object; ++o) renamed[static_cast<size_t>(o)] = o;
    for (size_t a = 0; a < hidden_alone.size(); ++a)
      renamed[static_cast<size_t>(hidden_alone[a].object)] = hidden_alone[static_cast<size_t>(find(static_cast<int>(a)))].object;
    int next = num_objects;
    std::vector<int> compact(static_cast<size_t>(next_object) + 1, 0);
    for (int o = num_objects + 1; o <= next_object; ++o)
      if (renamed[static_cast<size_t>(o)] == o) compact[static_cast<size_t>(o)] = ++next;
    if (next < next_object)  // new objects are only ever given to the segments' pixels
      for (int i : pixels)
        if (obj[i] > num_objects) obj[i] = compact[static_cast<size_t>(renamed[static_cast<size_t>(obj[i])])];
  }
  return objects;
}

}  // namespace clutterseg
