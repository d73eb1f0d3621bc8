#include "cloud.hpp"

#include <cmath>
#include <limits>
#include <unordered_map>

#include "clutterseg/smoothing.hpp"

namespace clutterseg::baselines {

pcl::PointCloud<PointT>::Ptr depth_to_cloud(const cv::Mat& depth, const Camera& camera, const cv::Mat& color) {
  if (depth.empty()) throw Error("depth image is empty");
  check_camera(camera, depth.cols, depth.rows, "camera");
  const cv::Mat metres = depth_to_metres(depth, camera);
  const bool has_color = !color.empty() && color.size() == depth.size() && color.type() == CV_8UC3;
  auto cloud = pcl::make_shared<pcl::PointCloud<PointT>>(depth.cols, depth.rows);
  cloud->is_dense = false;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int valid = 0;
  for (int v = 0; v < depth.rows; ++v) {
    const float* z = metres.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) {
      PointT& p = cloud->at(u, v);
      if (z[u] > 0 && std::isfinite(z[u])) {
        p.x = static_cast<float>((u - camera.cx) * z[u] / camera.fx);
        p.y = static_cast<float>((v - camera.cy) * z[u] / camera.fy);
        p.z = z[u];
        ++valid;
      } else {
        p.x = p.y = p.z = nan;
      }
      if (has_color) {
        const auto& c = color.at<cv::Vec3b>(v, u);
        p.b = c[0], p.g = c[1], p.r = c[2];
      } else {
        p.r = p.g = p.b = 128;
      }
      p.a = 255;
    }
  }
  if (valid == 0) throw Error("depth image has no valid measurement");
  return cloud;
}

int scaled_px(int px_at_640x480, const cv::Size& size) {
  const double scale = static_cast<double>(size.area()) / (640.0 * 480.0);
  return std::max(1, static_cast<int>(std::lround(px_at_640x480 * scale)));
}

cv::Mat compact_labels(const cv::Mat& labels) {
  cv::Mat out(labels.size(), CV_32S, cv::Scalar(0));
  std::unordered_map<int, int> renumber;
  for (int v = 0; v < labels.rows; ++v) {
    const int* in = labels.ptr<int>(v);
    int* o = out.ptr<int>(v);
    for (int u = 0; u < labels.cols; ++u) {
      if (in[u] == 0) continue;
      auto [it, added] = renumber.try_emplace(in[u], static_cast<int>(renumber.size()) + 1);
      o[u] = it->second;
    }
  }
  return out;
}

}  // namespace clutterseg::baselines
