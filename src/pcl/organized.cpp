// Organized multi-plane segmentation + Euclidean clusters with the planes excluded (Trevor et al. 2013),
// configured as PCL's apps/src/organized_segmentation_demo.cpp (docs/BASELINES.md lists each setting).
#include <pcl/common/angles.h>
#include <pcl/features/integral_image_normal.h>
#include <pcl/segmentation/euclidean_cluster_comparator.h>
#include <pcl/segmentation/organized_connected_component_segmentation.h>
#include <pcl/segmentation/organized_multi_plane_segmentation.h>

#include "clutterseg/pcl/baselines.hpp"
#include "cloud.hpp"

namespace clutterseg::baselines {

BaselineResult segment_organized(const cv::Mat& depth, const Camera& camera, const OrganizedParams& p) {
  QuietPcl quiet;
  BaselineResult out;
  Stopwatch clock(out.timings_ms);
  const auto cloud = depth_to_cloud(depth, camera, {});
  clock.mark("cloud");

  auto normals = pcl::make_shared<pcl::PointCloud<pcl::Normal>>();
  pcl::IntegralImageNormalEstimation<PointT, pcl::Normal> estimator;
  estimator.setNormalEstimationMethod(estimator.COVARIANCE_MATRIX);
  estimator.setMaxDepthChangeFactor(static_cast<float>(p.max_depth_change_factor));
  estimator.setNormalSmoothingSize(static_cast<float>(p.normal_smoothing_size));
  estimator.setInputCloud(cloud);
  estimator.compute(*normals);
  clock.mark("normals");

  const int min_inliers = scaled_px(p.min_plane_inliers, depth.size());
  pcl::OrganizedMultiPlaneSegmentation<PointT, pcl::Normal, pcl::Label> planes;
  planes.setMinInliers(static_cast<unsigned>(min_inliers));
  planes.setAngularThreshold(pcl::deg2rad(p.angular_threshold_deg));
  planes.setDistanceThreshold(p.distance_threshold);
  planes.setInputNormals(normals);
  planes.setInputCloud(cloud);
  std::vector<pcl::PlanarRegion<PointT>, Eigen::aligned_allocator<pcl::PlanarRegion<PointT>>> regions;
  std::vector<pcl::ModelCoefficients> coefficients;
  std::vector<pcl::PointIndices> inliers, label_indices, boundaries;
  auto plane_labels = pcl::make_shared<pcl::PointCloud<pcl::Label>>();
  if (p.refine_planes)
    planes.segmentAndRefine(regions, coefficients, inliers, plane_labels, label_indices, boundaries);
  else {
    std::vector<Eigen::Vector4f, Eigen::aligned_allocator<Eigen::Vector4f>> centroids;
    std::vector<Eigen::Matrix3f, Eigen::aligned_allocator<Eigen::Matrix3f>> covariances;
    planes.segment(coefficients, inliers, centroids, covariances, *plane_labels, label_indices);
  }
  clock.mark("planes");

  // Points on a plane (a plane label with more than min_inliers points, as the demo selects them) get
  // label 1, all others 0. PCL 1.13's EuclideanClusterComparator::compare() only links two points whose
  // labels are both *in* its "exclude" set, so the set given is {0}: the non-plane points.
  auto on_plane = pcl::make_shared<pcl::PointCloud<pcl::Label>>(cloud->width, cloud->height);
  for (auto& l : on_plane->points) l.label = 0;
  for (const auto& indices : label_indices)
    if (indices.indices.size() > static_cast<size_t>(min_inliers))
      for (int i : indices.indices) (*on_plane)[i].label = 1;
  auto keep = pcl::make_shared<std::set<std::uint32_t>>(std::set<std::uint32_t>{0});

  auto comparator = pcl::make_shared<pcl::EuclideanClusterComparator<PointT, pcl::Label>>();
  comparator->setInputCloud(cloud);
  comparator->setLabels(on_plane);
  comparator->setExcludeLabels(keep);
  comparator->setDistanceThreshold(static_cast<float>(p.cluster_distance), p.cluster_distance_depth_dependent);
  pcl::PointCloud<pcl::Label> cluster_labels;
  std::vector<pcl::PointIndices> clusters;
  pcl::OrganizedConnectedComponentSegmentation<PointT, pcl::Label> components(comparator);
  components.setInputCloud(cloud);
  components.segment(cluster_labels, clusters);
  clock.mark("clusters");

  // Clusters larger than the demo's size limit become objects; plane points are never in one because
  // the comparator never links them (a lone plane point is a cluster of one).
  const size_t min_cluster = static_cast<size_t>(scaled_px(p.min_cluster_px, depth.size()));
  cv::Mat labels(depth.size(), CV_32S, cv::Scalar(0));
  int next = 0;
  for (const auto& cluster : clusters) {
    if (cluster.indices.size() <= min_cluster) continue;
    ++next;
    for (int i : cluster.indices) labels.at<int>(i) = next;
  }
  out.labels = labels;
  clock.mark("labels");
  clock.total();
  return out;
}

}  // namespace clutterseg::baselines
