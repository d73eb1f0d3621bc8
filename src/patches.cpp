#include "clutterseg/patches.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>

namespace clutterseg {

std::vector<float> normal_histogram(const cv::Mat& normals, const std::vector<int>& pixels, int bins) {
  std::vector<float> hist(static_cast<size_t>(bins * bins), 0.f);
  if (pixels.empty()) return hist;
  const auto* n = normals.ptr<cv::Vec3f>();
  auto bin = [bins](float c) { return std::clamp(static_cast<int>((c + 1.f) * 0.5f * bins), 0, bins - 1); };
  for (int i : pixels) hist[bin(n[i][1]) * bins + bin(n[i][0])] += 1.f;
  const float inv = 1.f / static_cast<float>(pixels.size());
  for (auto& h : hist) h *= inv;
  return hist;
}

Patches extract_patches(const cv::Mat& edges, const cv::Mat& points, const cv::Mat& normals,
                        const Params::Patches& params, int min_size) {
  cv::Mat components, stats, centroids;
  const int count = cv::connectedComponentsWithStats(edges == 0, components, stats, centroids, 4, CV_32S);

  // Keep components of at least min_size pixels, numbered 1..N in OpenCV's (raster) order.
  std::vector<int> new_id(static_cast<size_t>(count), 0);
  Patches out;
  for (int c = 1; c < count; ++c) {
    if (stats.at<int>(c, cv::CC_STAT_AREA) < min_size) continue;
    Patch p;
    p.id = static_cast<int>(out.patches.size()) + 1;
    p.bbox = cv::Rect(stats.at<int>(c, cv::CC_STAT_LEFT), stats.at<int>(c, cv::CC_STAT_TOP),
                      stats.at<int>(c, cv::CC_STAT_WIDTH), stats.at<int>(c, cv::CC_STAT_HEIGHT));
    p.pixels.reserve(static_cast<size_t>(stats.at<int>(c, cv::CC_STAT_AREA)));
    new_id[static_cast<size_t>(c)] = p.id;
    out.patches.push_back(std::move(p));
  }
  out.labels = cv::Mat(edges.size(), CV_32S);
  const int total = static_cast<int>(edges.total());
  const int* comp = components.ptr<int>();
  int* lab = out.labels.ptr<int>();
  for (int i = 0; i < total; ++i) {
    const int id = new_id[static_cast<size_t>(comp[i])];
    lab[i] = id;
    if (id) out.patches[static_cast<size_t>(id - 1)].pixels.push_back(i);
  }

  const auto* pts = points.ptr<cv::Vec3f>();
  const auto* nrm = normals.ptr<cv::Vec3f>();
  for (auto& p : out.patches) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
    for (int i : p.pixels) {
      c += Eigen::Vector3d(pts[i][0], pts[i][1], pts[i][2]);
      n += Eigen::Vector3d(nrm[i][0], nrm[i][1], nrm[i][2]);
    }
    p.centroid = (c / static_cast<double>(p.pixels.size())).cast<float>();
    p.mean_normal = n.norm() > 0 ? Eigen::Vector3f(n.normalized().cast<float>()) : Eigen::Vector3f(0, 0, -1);
    // Mean angular deviation, taken as the angle of the mean normal's length: |mean of unit normals|
    // = mean cos(deviation) for small spreads; one acos per patch instead of one per pixel.
    p.spread_deg = static_cast<float>(std::acos(std::clamp(n.norm() / static_cast<double>(p.pixels.size()), 0.0, 1.0)) * 180.0 / M_PI);
    p.histogram = normal_histogram(normals, p.pixels, params.histogram_bins);
    p.occupied_bins = static_cast<int>(std::count_if(p.histogram.begin(), p.histogram.end(),
        [&](float h) { return h >= params.occupied_share; }));
    p.curved = p.occupied_bins >= params.flat_max_bins;
  }
  return out;
}

}  // namespace clutterseg
