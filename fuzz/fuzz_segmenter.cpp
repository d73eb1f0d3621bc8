// Whole small frames through a Segmenter with fuzzed intrinsics and parameters. Layout of the input:
//   bytes 0-47: fx, fy, cx, cy, depth_unit_m, theta_c as doubles (any bits: NaN, inf, huge)
//   bytes 48-63: width-1 (6 bits), height-1 (6 bits), temporal, median, and a few integer parameters
//   the rest: uint16 depth, row by row (repeated to fill the frame)
// Each frame goes through twice (the temporal window). Only clutterseg::Error may leave the library.
#include <cstdlib>
#include <cstring>

#include "clutterseg/segmenter.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace clutterseg;
  if (size < 66) return 0;
  double d[6];
  std::memcpy(d, data, sizeof d);
  const std::uint8_t* b = data + 48;
  Camera camera;
  camera.fx = d[0], camera.fy = d[1], camera.cx = d[2], camera.cy = d[3], camera.depth_unit_m = d[4];
  camera.width = 1 + (b[0] & 63), camera.height = 1 + (b[1] & 63);
  Params p;
  p.threads = 1;
  p.graph.theta_c = d[5];
  p.smoothing.temporal = b[2] & 1;
  p.smoothing.median = b[2] & 2;
  p.cutfree.enabled = b[2] & 4;
  p.coplanarity.enabled = b[2] & 8;
  p.curvature.enabled = b[2] & 16;
  p.support.enabled = b[2] & 32;
  p.support.objects_only = b[2] & 64;
  p.patches.split_band = (b[2] & 128) ? 0.0 : p.patches.split_band;
  p.patches.histogram_bins = static_cast<std::int8_t>(b[3]);
  p.normals.smooth_ksize = static_cast<std::int8_t>(b[4]);
  p.edges.step_px = static_cast<std::int8_t>(b[5]);
  p.patches.min_size_px = static_cast<std::int8_t>(b[6]);
  p.remaining.tiny_px = static_cast<std::int8_t>(b[7]);
  p.smoothing.temporal_frames = static_cast<std::int8_t>(b[8]);
  p.cutfree.planes = static_cast<std::int8_t>(b[9]);
  p.coplanarity.triples = static_cast<std::int8_t>(b[10]);
  p.adjacency.radius_px = static_cast<std::int8_t>(b[11]);
  p.seed = b[12];
  const std::uint8_t* pixels = data + 64;
  const std::size_t count = (size - 64) / 2;
  if (count == 0) return 0;
  cv::Mat depth(camera.height, camera.width, CV_16U);
  for (int i = 0; i < camera.width * camera.height; ++i) {
    std::uint16_t z;
    std::memcpy(&z, pixels + 2 * (static_cast<std::size_t>(i) % count), 2);
    depth.at<std::uint16_t>(i / camera.width, i % camera.width) = z;
  }
  try {
    Segmenter segmenter(p);
    for (int k = 0; k < 2; ++k) {
      const Result r = segmenter.segment(depth, camera);
      if (r.object_labels.size() != depth.size() || r.object_labels.type() != CV_32S) std::abort();
    }
  } catch (const Error&) {
  }
  return 0;
}
