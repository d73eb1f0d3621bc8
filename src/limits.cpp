// The valid range of every parameter, the largest frame: one place for the CLI, JSON, Python and ROS.
#include "clutterseg/limits.hpp"

#include <cmath>
#include <sstream>

#include "clutterseg/types.hpp"

namespace clutterseg {

namespace {

std::string shown(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// Each check names the key as --dump-config does. Ranges are closed; NaN fails every one.
void in_range(const char* key, double value, double lo, double hi) {
  if (!(value >= lo && value <= hi))
    throw Error(std::string("parameter '") + key + "' = " + shown(value) + ": must be a number in [" + shown(lo) +
                ", " + shown(hi) + "]");
}
void above(const char* key, double value, double lo, double hi) {  // (lo, hi]
  if (!(value > lo && value <= hi))
    throw Error(std::string("parameter '") + key + "' = " + shown(value) + ": must be a number in (" + shown(lo) +
                ", " + shown(hi) + "]");
}
void int_range(const char* key, int value, int lo, int hi) {
  if (value < lo || value > hi)
    throw Error(std::string("parameter '") + key + "' = " + std::to_string(value) + ": must be an integer in [" +
                std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

}  // namespace

void validate(const Params& p) {
  int_range("smoothing.temporal_frames", p.smoothing.temporal_frames, 1, 100);
  in_range("smoothing.temporal_band", p.smoothing.temporal_band, 0, 1);
  in_range("smoothing.scene_change_share", p.smoothing.scene_change_share, 0, 1);
  int_range("normals.step_px", p.normals.step_px, 1, 16);
  int_range("normals.smooth_ksize", p.normals.smooth_ksize, 1, 31);
  in_range("normals.noise_floor", p.normals.noise_floor, 0, 1);
  if (p.normals.smooth_ksize % 2 == 0)
    throw Error("parameter 'normals.smooth_ksize' = " + std::to_string(p.normals.smooth_ksize) + ": must be odd");
  in_range("edges.theta", p.edges.theta, 0, 1);
  int_range("edges.step_px", p.edges.step_px, 1, 16);
  above("edges.jump_slope", p.edges.jump_slope, 0, 1e6);
  int_range("patches.min_size_px", p.patches.min_size_px, 1, 100000);
  in_range("patches.metric_beyond_m", p.patches.metric_beyond_m, 0, 20);
  int_range("patches.histogram_bins", p.patches.histogram_bins, 2, 64);
  in_range("patches.occupied_share", p.patches.occupied_share, 0, 1);
  int_range("patches.flat_max_bins", p.patches.flat_max_bins, 1, 64 * 64);
  in_range("patches.split_band", p.patches.split_band, 0, 1);
  in_range("patches.seam_theta", p.patches.seam_theta, 0, 1);
  in_range("patches.seam_spread_deg", p.patches.seam_spread_deg, 0, 90);
  in_range("adjacency.radius_px", p.adjacency.radius_px, 0, 50);
  above("adjacency.d_max", p.adjacency.d_max, 0, 1);
  int_range("cutfree.planes", p.cutfree.planes, 1, 1000);
  above("cutfree.band", p.cutfree.band, 0, 1);
  in_range("cutfree.wrong_side_fraction", p.cutfree.wrong_side_fraction, 0, 1);
  in_range("cutfree.skip_angle_deg", p.cutfree.skip_angle_deg, 0, 180);
  in_range("cutfree.split_share", p.cutfree.split_share, 0, 0.5);
  in_range("convexity.tolerance", p.convexity.tolerance, 0, 2);
  in_range("convexity.step", p.convexity.step, 0, 1);
  in_range("convexity.concave_weight", p.convexity.concave_weight, 0, 1);
  in_range("convexity.top_angle_deg", p.convexity.top_angle_deg, 0, 90);
  in_range("convexity.step_offset", p.convexity.step_offset, 0, 1);
  in_range("coplanarity.angle_deg", p.coplanarity.angle_deg, 0, 180);
  int_range("coplanarity.triples", p.coplanarity.triples, 1, 10000);
  int_range("coplanarity.lines", p.coplanarity.lines, 1, 1000);
  in_range("coplanarity.behind_fraction", p.coplanarity.behind_fraction, 0, 1);
  in_range("coplanarity.behind_tolerance", p.coplanarity.behind_tolerance, 0, 1);
  in_range("coplanarity.lines_pass", p.coplanarity.lines_pass, 0, 1);
  in_range("coplanarity.max_gap", p.coplanarity.max_gap, 0, 10);
  in_range("coplanarity.planar_share", p.coplanarity.planar_share, 0, 1);
  in_range("coplanarity.planar_band", p.coplanarity.planar_band, 0, 1);
  in_range("coplanarity.front_fraction", p.coplanarity.front_fraction, 0, 1);
  in_range("curvature.theta_h", p.curvature.theta_h, 0, 1);
  in_range("curvature.line_fit", p.curvature.line_fit, 0, 1);
  in_range("curvature.neighbour_gap_px", p.curvature.neighbour_gap_px, 0, 50);
  in_range("curvature.concentric", p.curvature.concentric, 0, 1);
  in_range("curvature.open_centre", p.curvature.open_centre, 0, 10);
  in_range("curvature.split_inside", p.curvature.split_inside, 0, 1);
  in_range("graph.theta_c", p.graph.theta_c, 0, 1000);
  in_range("remaining.grow_distance", p.remaining.grow_distance, 0, 1);
  in_range("remaining.gap_px", p.remaining.gap_px, 0, 16);
  int_range("remaining.tiny_px", p.remaining.tiny_px, 0, 100000);
  in_range("remaining.min_contact_share", p.remaining.min_contact_share, 0, 1);
  int_range("remaining.hole_px", p.remaining.hole_px, 0, 1000);
  in_range("remaining.shadow_baseline", p.remaining.shadow_baseline, -1, 1);
  in_range("remaining.occluded_jump", p.remaining.occluded_jump, 0, 1);
  in_range("remaining.hidden_coplanar_band", p.remaining.hidden_coplanar_band, 0, 1);
  in_range("remaining.speck_band", p.remaining.speck_band, 0, 1);
  above("support.plane_band", p.support.plane_band, 0, 1);
  in_range("support.pixel_band", p.support.pixel_band, 0, 1);
  in_range("support.table_angle_deg", p.support.table_angle_deg, 0, 90);
  in_range("support.max_height", p.support.max_height, 0, 100);
  in_range("support.contact_distance", p.support.contact_distance, 0, 10);
  in_range("support.region_margin", p.support.region_margin, 0, 10);
  in_range("support.wall_min_extent", p.support.wall_min_extent, 0, 100);
  in_range("support.wall_hides_share", p.support.wall_hides_share, 0, 1);
  in_range("support.glued_share", p.support.glued_share, 0, 1);
  in_range("support.enclosed_share", p.support.enclosed_share, 0, 1);
  in_range("support.curved_bins_ratio", p.support.curved_bins_ratio, 0, 1000);
  int_range("tracking.max_missed", p.tracking.max_missed, 0, 100000);
  above("tracking.max_step", p.tracking.max_step, 0, 100);
  in_range("tracking.merge_share", p.tracking.merge_share, 0, 1);
  int_range("tracking.max_id", p.tracking.max_id, 1, 65535);
  int_range("threads", p.threads, 0, 256);
}

void check_frame_size(std::int64_t width, std::int64_t height, const std::string& what) {
  if (width <= 0 || height <= 0) throw Error(what + ": image is empty");
  if (width > kMaxFrameSide || height > kMaxFrameSide || width * height > kMaxFramePixels)
    throw Error(what + ": " + std::to_string(width) + "x" + std::to_string(height) +
                " is beyond the largest frame clutterseg takes (" + std::to_string(kMaxFramePixels) +
                " pixels, " + std::to_string(kMaxFrameSide) + " a side; about 85 bytes of memory per pixel)");
}

}  // namespace clutterseg
