// Labels for pixels without depth that an object encloses (include/clutterseg/holes.hpp).
#include "clutterseg/holes.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace clutterseg {
namespace {

// The share of a shadow run next to the occluder left unlabelled: where the occluder shows a side face to the
// camera, that face has no depth either (the projector does not light it), and its width is unknown. Measured
// on the Table II families: 0.3 and 0.4 alike, 0 gives the occluder's face to the far object, 0.5 and more
// lose shadow pixels (docs/RESULTS.md, Issue 14, third pass).
constexpr double kOccluderShare = 0.3;

inline std::uint64_t word_at(const uchar* p) {
  std::uint64_t w;
  std::memcpy(&w, p, 8);
  return w;
}

// Whether any of the 16 mask bytes at h (0 or 255) is set where the byte at `above` is not: h & ~above.
// One SSE2 test for 16 pixels where the scans below skip most of a row.
inline bool any_new16(const uchar* h, const uchar* above) {
#if defined(__SSE2__)
  const __m128i new_bytes = _mm_andnot_si128(_mm_loadu_si128(reinterpret_cast<const __m128i*>(above)),
                                             _mm_loadu_si128(reinterpret_cast<const __m128i*>(h)));
  return _mm_movemask_epi8(new_bytes) != 0;  // bytes are 0 or 255: their top bits tell
#else
  return ((word_at(h) & ~word_at(above)) | (word_at(h + 8) & ~word_at(above + 8))) != 0;
#endif
}

}  // namespace

int fill_depth_holes(cv::Mat& object_labels, const cv::Mat& depth, std::vector<Object>& objects, int max_run,
                     double shadow_focal) {
  CV_Assert(object_labels.type() == CV_32S && depth.type() == CV_32F && object_labels.size() == depth.size());
  if (max_run <= 0) return 0;
  const int rows = depth.rows, cols = depth.cols, m = static_cast<int>(objects.size());
  std::vector<uchar> takes(static_cast<size_t>(m) + 1, 0);  // objects that may take pixels
  for (int k = 1; k <= m; ++k) takes[static_cast<size_t>(k)] = !objects[static_cast<size_t>(k - 1)].support &&
                                                              !objects[static_cast<size_t>(k - 1)].background;
  const auto candidate = [&](int a, int b) { return a > 0 && a == b && a <= m && takes[static_cast<size_t>(a)] ? a : 0; };
  // The projector's shadow of an occluder's edge (beyond the paper): the run [begin, end) of a row lies on
  // the far surface, on the side away from the projector (left of the occluder for a projector along +x),
  // and is at most f * b * (1 / z_near - 1 / z_far) pixels wide, plus `slack` for the dropouts beside it (a
  // structured-light sensor's matching window reaching into the shadow).
  const auto shadow_owner = [&](const float* d, const int* l, int begin, int end, double fb, int slack) {
    const int far_at = fb > 0 ? begin - 1 : end, near_at = fb > 0 ? end : begin - 1;
    const float z_far = d[far_at], z_near = d[near_at];
    if (!valid_depth(z_far) || !valid_depth(z_near) || z_near >= z_far) return 0;
    if (end - begin > std::abs(fb) * (1.0 / z_near - 1.0 / z_far) + slack) return 0;
    const int k = l[far_at];
    return k > 0 && k <= m && k != l[near_at] && takes[static_cast<size_t>(k)] ? k : 0;
  };
  // Holes (no measurement, NaN included, and no label) in a byte mask, 255 = hole, in a vector loop; the
  // scans below skip eight pixels at a time.
  cv::Mat mask(rows, cols, CV_8U);
  for (int y = 0; y < rows; ++y) {
    const float* d = depth.ptr<float>(y);
    const int* lab = object_labels.ptr<int>(y);
    uchar* h = mask.ptr<uchar>(y);
    int x = 0;
#if defined(__SSE2__)
    // 16 pixels at a time (the compiler leaves this loop scalar): measured or labelled -> 0, else 255.
    const __m128 zero = _mm_setzero_ps();
    const __m128i izero = _mm_setzero_si128();
    for (; x + 16 <= cols; x += 16) {
      __m128i keep[4];
      for (int q = 0; q < 4; ++q) {
        const __m128i measured = _mm_castps_si128(_mm_cmpgt_ps(_mm_loadu_ps(d + x + 4 * q), zero));
        const __m128i unlabelled = _mm_cmpeq_epi32(_mm_loadu_si128(reinterpret_cast<const __m128i*>(lab + x + 4 * q)), izero);
        keep[q] = _mm_andnot_si128(measured, unlabelled);  // -1 = hole
      }
      const __m128i bytes = _mm_packs_epi16(_mm_packs_epi32(keep[0], keep[1]), _mm_packs_epi32(keep[2], keep[3]));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(h + x), bytes);
    }
#endif
    for (; x < cols; ++x) h[x] = ((d[x] > 0.f) | (lab[x] != 0)) ? 0 : 255;
  }
  constexpr std::uint64_t kAllHoles = ~std::uint64_t{0};
  const std::vector<uchar> no_holes(static_cast<size_t>(cols), 0);  // `above` for the row scan's test
  int filled = 0;
  // Rows. The fills go straight into the labels: they only touch holes, and both scans read the labels of
  // non-holes only, so the column scan below decides as if it ran first.
  for (int y = 0; y < rows; ++y) {
    const uchar* h = mask.ptr<uchar>(y);
    int* l = object_labels.ptr<int>(y);
    int x = 0;
    while (x < cols) {
      if (x + 16 <= cols && !any_new16(h + x, no_holes.data() + x)) { x += 16; continue; }
      if (x + 8 <= cols && word_at(h + x) == 0) { x += 8; continue; }
      if (!h[x]) { ++x; continue; }
      const int begin = x;
      while (x + 8 <= cols && word_at(h + x) == kAllHoles) x += 8;
      while (x < cols && h[x]) ++x;
      if (begin == 0 || x == cols) continue;
      int k = x - begin <= max_run ? candidate(l[begin - 1], l[x]) : 0;
      int from = begin, to = x;
      if (!k && shadow_focal != 0 && (k = shadow_owner(depth.ptr<float>(y), l, begin, x, shadow_focal, max_run / 2))) {
        // The occluder's own side face, unlit by the projector too, may fill the part next to it: that stays 0.
        const int near = static_cast<int>(std::lround(kOccluderShare * (x - begin)));
        if (shadow_focal > 0) to -= near; else from += near;
      }
      if (!k) continue;
      std::fill(l + from, l + to, k);
      filled += to - from;
      objects[static_cast<size_t>(k - 1)].pixel_count += to - from;
    }
  }
  // Columns: a run starts at a hole below a non-hole; walk down at most max_run + 1 pixels. A pixel the
  // row scan gave to another object is claimed by two: nobody's.
  for (int y = 1; y < rows; ++y) {
    const uchar* h = mask.ptr<uchar>(y);
    const uchar* above = mask.ptr<uchar>(y - 1);
    for (int x = 0; x < cols; ++x) {
      if (x + 16 <= cols && !any_new16(h + x, above + x)) { x += 15; continue; }
      if (x + 8 <= cols && (word_at(h + x) & ~word_at(above + x)) == 0) { x += 7; continue; }
      if (!h[x] || above[x]) continue;
      int end = y;
      while (end < rows && end - y <= max_run && mask.ptr<uchar>(end)[x]) ++end;
      if (end == rows || end - y > max_run) continue;
      const int k = candidate(object_labels.ptr<int>(y - 1)[x], object_labels.ptr<int>(end)[x]);
      if (!k) continue;
      for (int yy = y; yy < end; ++yy) {
        int& l = object_labels.ptr<int>(yy)[x];
        if (l == k) continue;
        if (l == 0) {
          l = k;
          ++filled;
          ++objects[static_cast<size_t>(k - 1)].pixel_count;
        } else {  // the row scan gave it to another object
          --objects[static_cast<size_t>(l - 1)].pixel_count;
          --filled;
          l = 0;
        }
      }
    }
  }
  return filled;
}

}  // namespace clutterseg
