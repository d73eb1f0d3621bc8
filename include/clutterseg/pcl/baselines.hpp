// The PCL segmenters clutterseg is compared with (library clutterseg_pcl). Same contract as clutterseg:
// depth + intrinsics in, object labels per pixel out (CV_32S, 0 = table, planes, no data), per-stage
// times in milliseconds. Every setting and where it comes from: docs/BASELINES.md.
#pragma once

#include "clutterseg/types.hpp"

namespace clutterseg::baselines {

struct BaselineResult {
  cv::Mat labels;      // CV_32S object ids 1..K, 0 = none (table, planes, no measurement)
  Timings timings_ms;  // per stage, last entry "total"
};

// SupervoxelClustering + LCCPSegmentation (Stein et al., CVPR 2014) with the defaults of PCL's
// examples/segmentation/example_lccp_segmentation.cpp.
struct LccpParams {
  double voxel_resolution = 0.0075;     // supervoxel octree voxel [m]
  double seed_resolution = 0.03;        // supervoxel seed spacing [m]
  double color_importance = 0.0;        // weight of colour distance [-]
  double spatial_importance = 1.0;      // weight of spatial distance [-]
  double normal_importance = 4.0;       // weight of normal distance [-]
  bool single_camera_transform = false; // depth-dependent voxel grid (example: off unless -tvoxel)
  bool refine_supervoxels = false;      // example: off unless -refine
  double concavity_tolerance_deg = 10;  // concave edges flatter than this count as convex [deg]
  double smoothness_threshold = 0.1;    // step invalidation, 0 strictest .. 1 off [-]
  bool extended_convexity = false;      // k factor 1 instead of 0 (example: off unless -ec)
  bool sanity_criterion = false;        // example: off unless -sc
  unsigned min_segment_size = 0;        // merge smaller segments [supervoxels] (example: 0)
  // Objects-only view (ours; the example labels every segment): a segment is dropped as table, wall or
  // other large plane when the plane fitted robustly to it holds at least plane_min_px of its pixels (at
  // 640x480, scaled with image area; the organized baseline's plane size) within plane_distance, and at
  // least plane_inlier_share of the segment.
  bool drop_planes = true;
  int plane_min_px = 10000;             // [px at 640x480]
  double plane_distance = 0.02;         // [m]
  double plane_inlier_share = 0.5;      // [-]
};

// Organized multi-plane segmentation + Euclidean clusters with the planes excluded (Trevor et al.,
// "Efficient organized point cloud segmentation with connected components", SPME workshop 2013), with the
// settings of PCL's apps/src/organized_segmentation_demo.cpp.
struct OrganizedParams {
  double max_depth_change_factor = 0.02;  // integral-image normals: depth change that breaks smoothing [m]
  double normal_smoothing_size = 20.0;    // integral-image normals: smoothing window [px]
  int min_plane_inliers = 10000;          // smallest plane [px at 640x480], scaled with image area
  double angular_threshold_deg = 3.0;     // normals of one plane differ by less than this [deg]
  double distance_threshold = 0.02;       // points of one plane lie within this of it [m]
  bool refine_planes = true;              // segmentAndRefine (the demo's default)
  double cluster_distance = 0.01;         // neighbouring pixels closer than this join a cluster [m]
  bool cluster_distance_depth_dependent = false;  // demo: off
  int min_cluster_px = 1000;              // smaller clusters are dropped [px at 640x480], scaled with area
};

// depth: CV_16U (times camera.depth_unit_m) or CV_32F metres, 0/NaN = no measurement. color: BGR of
// the same size or empty (LCCP ignores colour at colour importance 0). Throws Error on bad input.
BaselineResult segment_lccp(const cv::Mat& depth, const Camera& camera, const cv::Mat& color = {},
                            const LccpParams& params = {});
BaselineResult segment_organized(const cv::Mat& depth, const Camera& camera, const OrganizedParams& params = {});

}  // namespace clutterseg::baselines
