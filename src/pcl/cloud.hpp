// Shared by the PCL baselines: depth image -> organized PCL cloud, label bookkeeping, quiet PCL.
#pragma once

#include <pcl/console/print.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <chrono>

#include "clutterseg/stopwatch.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg::baselines {

using PointT = pcl::PointXYZRGBA;  // the point type of both PCL examples

// PCL logs warnings to stderr; the library must not print, so it is silenced while a baseline runs.
class QuietPcl {
 public:
  QuietPcl() : saved_(pcl::console::getVerbosityLevel()) { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); }
  ~QuietPcl() { pcl::console::setVerbosityLevel(saved_); }
  QuietPcl(const QuietPcl&) = delete;
  QuietPcl& operator=(const QuietPcl&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL saved_;
};

// Back-projects depth (CV_16U times depth_unit_m or CV_32F metres; 0/NaN = none) into an organized
// cloud of the image's size, NaN where there is no measurement. Colour (BGR) is copied when given.
pcl::PointCloud<PointT>::Ptr depth_to_cloud(const cv::Mat& depth, const Camera& camera, const cv::Mat& color);

// Scales a pixel count given for 640x480 to the image's area (at least 1).
int scaled_px(int px_at_640x480, const cv::Size& size);

// Relabels a label image so that the kept labels become 1..K in row-major order of first appearance.
cv::Mat compact_labels(const cv::Mat& labels);


}  // namespace clutterseg::baselines
