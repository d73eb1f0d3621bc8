// Plain data passed between the stages. Images are cv::Mat; label images are CV_32S with 0 = none.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace clutterseg {

// Every failure of the library: a one-line message that names the input and the problem.
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Pinhole intrinsics of the depth image, plus the unit of integer depth.
struct Camera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double depth_unit_m = 0.001;  // metres per integer depth step (uint16 input)
  Eigen::Matrix4d camera_to_robot = Eigen::Matrix4d::Identity();  // pose for 3D outputs
};

// A depth (the z of a cloud point) that is a measurement: finite and > 0 (NaN compares false). Branch-free,
// so per-pixel loops that use it still vectorise.
inline bool valid_depth(float z) { return (z > 0) & (z < std::numeric_limits<float>::infinity()); }

// A point of an organized cloud (depth_to_points) that has a measurement: pixels without one are (0,0,0).
inline bool valid_point(const cv::Vec3f& p) { return valid_depth(p[2]); }

// Squared distance of two points: cv::Vec3f's difference and dot written out, the same operations in the
// same order (OpenCV's generic loops were a tenth of the time of the loops that call this per pixel).
inline float distance2(const cv::Vec3f& a, const cv::Vec3f& b) {
  const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

// End of the run of labels equal to lab[begin] within [begin, end). Label images come in long runs
// (the row segments of patches and objects): sixteen labels per SSE2 test, and the test that fails gives
// the end at once (the first lane that differs; runs are also many and short: edge bands, object rows);
// near `end`, eight per step read as four 64-bit words each holding two labels (the OR of differences is 0
// only when all eight match).
inline int run_end(const int* lab, int begin, int end) {
  const int id = lab[begin];
  int k = begin + 1;
#if defined(__SSE2__)
  const __m128i ids = _mm_set1_epi32(id);
  for (; k + 16 <= end; k += 16) {
    const auto* four = reinterpret_cast<const __m128i*>(lab + k);
    const __m128i same[4] = {_mm_cmpeq_epi32(_mm_loadu_si128(four), ids), _mm_cmpeq_epi32(_mm_loadu_si128(four + 1), ids),
                             _mm_cmpeq_epi32(_mm_loadu_si128(four + 2), ids), _mm_cmpeq_epi32(_mm_loadu_si128(four + 3), ids)};
    if (_mm_movemask_epi8(_mm_and_si128(_mm_and_si128(same[0], same[1]), _mm_and_si128(same[2], same[3]))) == 0xFFFF) continue;
    unsigned equal = 0;  // bit j: label k + j equals id
    for (int q = 0; q < 4; ++q) equal |= static_cast<unsigned>(_mm_movemask_ps(_mm_castsi128_ps(same[q]))) << (4 * q);
    return k + __builtin_ctz(~equal);  // the trailing ones (C++17: this header is also the ROS node's)
  }
#endif
  const int two[2] = {id, id};
  std::uint64_t pair;
  std::memcpy(&pair, two, sizeof pair);
  for (; k + 8 <= end; k += 8) {
    std::uint64_t w[4];
    std::memcpy(w, lab + k, sizeof w);
    if (((w[0] ^ pair) | (w[1] ^ pair) | (w[2] ^ pair) | (w[3] ^ pair)) != 0) break;
  }
  while (k < end && lab[k] == id) ++k;
  return k;
}

// In a word of eight bytes read with memcpy, `marks` holding a set bit in each marked byte and none in
// the bytes before the first marked one (in memory order): the index (0-7) of that first marked byte.
// Little-endian only (the callers fall back to a byte loop elsewhere).
inline int first_marked_byte(std::uint64_t marks) { return __builtin_ctzll(marks) / 8; }
constexpr bool kLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;  // C++17: no std::endian here

// First index in [from, end) where bytes[i] != 0, or end. Masks with few set bytes (pixels next to holes,
// edge carriers) are skipped eight bytes per step.
inline int first_nonzero(const std::uint8_t* bytes, int from, int end) {
  if (from < end && bytes[from]) return from;  // inside a run of set bytes
  for (; from + 8 <= end; from += 8) {
    std::uint64_t eight;
    std::memcpy(&eight, bytes + from, sizeof eight);
    if (!eight) continue;
    if constexpr (kLittleEndian) return from + first_marked_byte(eight);
    break;
  }
  while (from < end && !bytes[from]) ++from;
  return from;
}

// First index in [from, end) where bytes[i] == 0, or end; eight bytes per step through set ones.
inline int first_zero(const std::uint8_t* bytes, int from, int end) {
  if (from < end && !bytes[from]) return from;  // inside a run of zeros
  constexpr std::uint64_t kOnes = 0x0101010101010101ull, kHighs = 0x8080808080808080ull;
  for (; from + 8 <= end; from += 8) {
    std::uint64_t eight;
    std::memcpy(&eight, bytes + from, sizeof eight);
    // The high bit of every zero byte; a byte after a zero one may be marked too (a borrow), none before.
    const std::uint64_t zeros = (eight - kOnes) & ~eight & kHighs;
    if (!zeros) continue;
    if constexpr (kLittleEndian) return from + first_marked_byte(zeros);
    break;
  }
  while (from < end && bytes[from]) ++from;
  return from;
}

// The root of x's set in a union-find forest (`parent[i] == i` for a root), halving the path on the way: every
// union-find of the library (patch runs, the graph cut, table groups, hidden parts) uses this one.
inline int find_root(std::vector<int>& parent, int x) {
  while (parent[static_cast<size_t>(x)] != x) x = parent[static_cast<size_t>(x)] = parent[static_cast<size_t>(parent[static_cast<size_t>(x)])];
  return x;
}

// The most pixels a per-patch statistic reads (a RANSAC sample, a share, a fit): `vga` in a 640x480 frame,
// and in a smaller frame that many times its share of VGA's pixels (a quarter at 320x240, never less), so
// that every frame samples the scene as densely and a smaller frame spends proportionally less per patch,
// as the per-pixel stages do. Larger frames keep the VGA budget: work per patch stays bounded.
inline size_t sample_budget(size_t vga, size_t frame_pixels) {
  constexpr size_t kVga = 640 * 480;
  const size_t pixels = std::clamp(frame_pixels, kVga / 4, kVga);
  return std::max<size_t>(1, vga * pixels / kVga);
}
inline size_t sample_budget(size_t vga, const cv::Mat& image) { return sample_budget(vga, image.total()); }

// Checks intrinsics against an image; throws Error("<what>: ...") when they do not fit.
void check_camera(const Camera& camera, int width, int height, const std::string& what);

// One surface patch (paper c): statistics over its core pixels, before edge pixels are assigned.
struct Patch {
  int id = 0;                          // label in the patch image (1..N)
  std::vector<int> pixels;             // linear indices y * width + x of its core pixels
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();     // camera frame [m]
  Eigen::Vector3f mean_normal = Eigen::Vector3f::Zero();  // unit, facing the camera
  float spread_deg = 0;                // mean angle of pixel normals to the mean normal
  std::vector<float> histogram;        // bins x bins shares of normal (x, y); sums to 1
  int occupied_bins = 0;               // bins with share >= Params::Patches::occupied_share
  bool curved = false;                 // occupied_bins >= flat_max_bins
  cv::Rect bbox;                       // image bounding box
  bool table = false;                  // lies in the support plane (support.hpp)
};

// Why two patches are linked in the graph.
// AdjacentConcave: adjacent, meeting in a concave crease (contact.hpp), weighted down by the graph.
enum class Cue : std::uint8_t { Adjacent, Coplanar, CurvatureOpen, CurvatureOccluded, AdjacentConcave };
const char* to_string(Cue cue);

struct GraphEdge {
  int a = 0, b = 0;    // patch indices (0-based into the patch table), a < b
  Cue cue = Cue::Adjacent;
  float weight = 0;    // symmetrised 1/deg weight (paper i)
  float convexity = std::numeric_limits<float>::quiet_NaN();  // adjacent links: PairJunction::convexity
};

struct OrientedBox {
  Eigen::Vector3f center = Eigen::Vector3f::Zero();
  Eigen::Matrix3f axes = Eigen::Matrix3f::Identity();  // columns: unit axes, largest extent first
  Eigen::Vector3f extents = Eigen::Vector3f::Zero();    // full side lengths along the axes [m]
};

struct Plane {
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();  // unit, facing the camera
  float offset = 0;                                   // normal . x + offset = 0
  float distance(const Eigen::Vector3f& x) const { return normal.dot(x) + offset; }
};

struct Object {
  int id = 0;                     // label in the object image: 1..M, or its track id (Params::Tracking)
  int pixel_count = 0;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // robot frame if a pose is given [m]
  OrientedBox box;                // robot frame if a pose is given
  std::vector<int> patches;       // patch indices (0-based)
  float cut_cost = 0;             // cost of the cheapest cut that would split it; +inf for one patch
  bool support = false;           // the table the objects stand on
  bool background = false;        // walls and far surfaces
  // Tracking (tracking.hpp); without it every object is new: age 1, the rest 0 or empty.
  int age = 1;                    // frames since it was first seen, this one included [frames]
  int frames_missed = 0;          // frames it was unseen just before this one (0 = seen in the previous)
  int split_from = 0;             // id of the object it split off from (0 = none)
  std::vector<int> merged_with;   // ids of remembered objects merged into it (Tracker: merge)
};

// Per-stage wall-clock times in milliseconds, in pipeline order; the last entry is "total".
using Timings = std::vector<std::pair<std::string, double>>;

}  // namespace clutterseg
