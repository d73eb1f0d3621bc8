// SupervoxelClustering + LCCPSegmentation, configured as PCL's example_lccp_segmentation.cpp does by
// default (docs/BASELINES.md lists each setting with its source).
#include <pcl/segmentation/lccp_segmentation.h>
#include <pcl/segmentation/supervoxel_clustering.h>

#include <Eigen/Eigenvalues>
#include <map>

#include "clutterseg/pcl/baselines.hpp"
#include "cloud.hpp"

namespace clutterseg::baselines {

namespace {

// Least-squares plane (unit normal, point on it) of the points idx, by PCA.
std::pair<Eigen::Vector3d, Eigen::Vector3d> fit_plane(const pcl::PointCloud<PointT>& cloud, const std::vector<int>& idx) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : idx) mean += cloud[i].getVector3fMap().cast<double>();
  mean /= static_cast<double>(idx.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : idx) {
    const Eigen::Vector3d d = cloud[i].getVector3fMap().cast<double>() - mean;
    cov += d * d.transpose();
  }
  return {Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0), mean};
}

// Segments that are mainly a large plane (table, walls): the plane fitted to the segment and refitted to
// its own inliers (within plane_distance) a few times, so that objects LCCP merged into the table do not
// tilt it, holds at least plane_min_px points and plane_inlier_share of the segment. The plane size and
// distance are the organized baseline's, so both baselines drop the same kind of surface.
void drop_planar_segments(cv::Mat& labels, const pcl::PointCloud<PointT>& cloud, const LccpParams& p) {
  constexpr int kRefits = 5;
  const size_t min_px = static_cast<size_t>(scaled_px(p.plane_min_px, labels.size()));
  double max_label = 0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  const int count = static_cast<int>(max_label);
  std::vector<std::vector<int>> members(count + 1);
  for (int i = 0; i < static_cast<int>(labels.total()); ++i)
    if (int l = labels.at<int>(i); l > 0) members[l].push_back(i);
  for (int l = 1; l <= count; ++l) {
    const auto& idx = members[l];
    if (idx.size() < min_px) continue;
    std::vector<int> inliers = idx;
    for (int round = 0; round < kRefits && inliers.size() >= min_px; ++round) {
      const auto [normal, origin] = fit_plane(cloud, inliers);
      std::vector<int> next;
      for (int i : idx)
        if (std::abs(normal.dot(cloud[i].getVector3fMap().cast<double>() - origin)) <= p.plane_distance) next.push_back(i);
      if (next == inliers) break;
      inliers = std::move(next);
    }
    if (inliers.size() >= min_px && inliers.size() >= p.plane_inlier_share * idx.size())
      for (int i : idx) labels.at<int>(i) = 0;
  }
}

}  // namespace

BaselineResult segment_lccp(const cv::Mat& depth, const Camera& camera, const cv::Mat& color, const LccpParams& p) {
  QuietPcl quiet;
  BaselineResult out;
  Stopwatch clock(out.timings_ms);
  const auto cloud = depth_to_cloud(depth, camera, color);
  clock.mark("cloud");

  const auto voxel = static_cast<float>(p.voxel_resolution), seed = static_cast<float>(p.seed_resolution);
  pcl::SupervoxelClustering<PointT> supervoxels(voxel, seed);
  supervoxels.setUseSingleCameraTransform(p.single_camera_transform);  // set explicitly, as the example does
  supervoxels.setInputCloud(cloud);
  supervoxels.setColorImportance(static_cast<float>(p.color_importance));
  supervoxels.setSpatialImportance(static_cast<float>(p.spatial_importance));
  supervoxels.setNormalImportance(static_cast<float>(p.normal_importance));
  std::map<std::uint32_t, pcl::Supervoxel<PointT>::Ptr> clusters;
  supervoxels.extract(clusters);
  if (p.refine_supervoxels) supervoxels.refineSupervoxels(2, clusters);
  std::multimap<std::uint32_t, std::uint32_t> adjacency;
  supervoxels.getSupervoxelAdjacency(adjacency);
  clock.mark("supervoxels");

  cv::Mat labels(depth.size(), CV_32S, cv::Scalar(0));
  if (!clusters.empty()) {
    pcl::LCCPSegmentation<PointT> lccp;
    lccp.setConcavityToleranceThreshold(static_cast<float>(p.concavity_tolerance_deg));
    lccp.setSanityCheck(p.sanity_criterion);
    lccp.setSmoothnessCheck(true, voxel, seed, static_cast<float>(p.smoothness_threshold));
    lccp.setKFactor(p.extended_convexity ? 1 : 0);
    lccp.setInputSupervoxels(clusters, adjacency);
    lccp.setMinSegmentSize(p.min_segment_size);
    lccp.segment();
    clock.mark("lccp");

    // The labelled cloud has one point per input point, in image order (NaN points get label 0).
    const auto labelled = supervoxels.getLabeledCloud();
    lccp.relabelCloud(*labelled);
    if (labelled->size() == labels.total())
      for (size_t i = 0; i < labelled->size(); ++i) labels.at<int>(static_cast<int>(i)) = static_cast<int>((*labelled)[i].label);
    labels = compact_labels(labels);
    if (p.drop_planes) drop_planar_segments(labels, *cloud, p);
    labels = compact_labels(labels);
  } else {
    clock.mark("lccp");
  }
  out.labels = labels;
  clock.mark("labels");
  clock.total();
  return out;
}

}  // namespace clutterseg::baselines
