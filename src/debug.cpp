#include "clutterseg/debug.hpp"

#include <opencv2/imgproc.hpp>

namespace clutterseg {

cv::Mat render_normals(const NormalPlanes& planes) {
  cv::Mat normals;
  cv::merge(planes.data(), planes.size(), normals);
  cv::Mat bgr(normals.size(), CV_8UC3, cv::Scalar::all(0));
  normals.forEach<cv::Vec3f>([&](const cv::Vec3f& n, const int* pos) {
    if (n[2] == 0) return;
    // x, y, z in [-1, 1] -> R, G, B; OpenCV stores BGR.
    auto c = [](float v) { return cv::saturate_cast<uchar>((v + 1.f) * 127.5f); };
    bgr.at<cv::Vec3b>(pos[0], pos[1]) = cv::Vec3b(c(-n[2]), c(n[1]), c(n[0]));
  });
  return bgr;
}

cv::Mat render_edges(const cv::Mat& edges) { return 255 - edges; }

cv::Mat render_edge_value(const cv::Mat& edge_value) {
  cv::Mat grey;
  edge_value.convertTo(grey, CV_8U, 510.0, -255.0);  // [0.5, 1] -> [0, 255]
  return grey;
}

namespace {
cv::Vec3b label_colour(int id) {
  // Golden-ratio hue steps give neighbouring ids clearly different colours.
  const double h = std::fmod(id * 0.618033988749895, 1.0) * 180.0;
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(h, 200 + (id * 37) % 56, 200 + (id * 53) % 56)), bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  return bgr.at<cv::Vec3b>(0, 0);
}
}  // namespace

cv::Mat render_labels(const cv::Mat& labels) {
  double max_id = 0;
  cv::minMaxLoc(labels, nullptr, &max_id);
  std::vector<cv::Vec3b> lut(static_cast<size_t>(max_id) + 1, cv::Vec3b(0, 0, 0));
  for (size_t i = 1; i < lut.size(); ++i) lut[i] = label_colour(static_cast<int>(i));
  cv::Mat bgr(labels.size(), CV_8UC3);
  labels.forEach<int>([&](const int& id, const int* pos) {
    bgr.at<cv::Vec3b>(pos[0], pos[1]) = id > 0 ? lut[static_cast<size_t>(id)] : cv::Vec3b(0, 0, 0);
  });
  return bgr;
}

cv::Mat render_depth(const cv::Mat& depth_m) {
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth_m, &lo, &hi, nullptr, nullptr, depth_m > 0);
  cv::Mat scaled, bgr;
  depth_m.convertTo(scaled, CV_8U, hi > lo ? 255.0 / (hi - lo) : 1.0, hi > lo ? -lo * 255.0 / (hi - lo) : 0);
  cv::applyColorMap(scaled, bgr, cv::COLORMAP_TURBO);
  bgr.setTo(cv::Scalar::all(0), depth_m <= 0);
  return bgr;
}

cv::Mat render_overlay(const cv::Mat& labels, const cv::Mat& color, const cv::Mat& depth_m) {
  cv::Mat base;
  if (!color.empty() && color.size() == labels.size()) {
    base = color.channels() == 3 ? color.clone() : cv::Mat();
    if (color.channels() == 1) cv::cvtColor(color, base, cv::COLOR_GRAY2BGR);
    if (color.channels() == 4) cv::cvtColor(color, base, cv::COLOR_BGRA2BGR);
  } else {
    cv::Mat gray;
    cv::cvtColor(render_depth(depth_m), gray, cv::COLOR_BGR2GRAY);
    cv::cvtColor(gray, base, cv::COLOR_GRAY2BGR);
  }
  cv::Mat overlay;
  cv::addWeighted(base, 0.45, render_labels(labels), 0.55, 0, overlay);
  overlay.setTo(cv::Scalar::all(0), labels == 0);
  cv::Mat dim = base * 0.5;
  dim.copyTo(overlay, labels == 0);
  // Thin dark outline around every label for legibility.
  // OpenCV morphology has no int32 kernel; float holds every id below 2^24 exactly.
  cv::Mat ids, grow, shrink;
  labels.convertTo(ids, CV_32F);
  cv::dilate(ids, grow, cv::Mat());
  cv::erode(ids, shrink, cv::Mat());
  overlay.setTo(cv::Scalar(20, 20, 20), (grow != shrink) & (labels > 0));
  return overlay;
}

cv::Mat render_graph(const Result& result, const Camera& camera) {
  cv::Mat img = render_labels(result.patch_labels) * 0.6;
  auto centre = [&](int patch) {
    const auto& c = result.patches[static_cast<size_t>(patch)].centroid;
    return cv::Point(static_cast<int>(camera.fx * c.x() / c.z() + camera.cx),
                     static_cast<int>(camera.fy * c.y() / c.z() + camera.cy));
  };
  for (const auto& e : result.graph) {
    cv::Scalar colour;
    switch (e.cue) {
      case Cue::Adjacent: colour = cv::Scalar(255, 255, 255); break;
      case Cue::Coplanar: colour = cv::Scalar(0, 255, 0); break;
      case Cue::CurvatureOpen: colour = cv::Scalar(255, 128, 0); break;
      case Cue::CurvatureOccluded: colour = cv::Scalar(0, 200, 255); break;
      case Cue::AdjacentConcave: colour = cv::Scalar(0, 0, 255); break;
    }
    cv::line(img, centre(e.a), centre(e.b), colour, 1 + static_cast<int>(e.weight * 4), cv::LINE_AA);
  }
  for (size_t i = 0; i < result.patches.size(); ++i) {
    cv::circle(img, centre(static_cast<int>(i)), 3, cv::Scalar(0, 0, 255), cv::FILLED, cv::LINE_AA);
    cv::putText(img, std::to_string(i + 1), centre(static_cast<int>(i)) + cv::Point(4, -4),
                cv::FONT_HERSHEY_SIMPLEX, 0.35, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  }
  // Legend: one line per cue.
  const std::pair<const char*, cv::Scalar> legend[] = {{"adjacent", {255, 255, 255}}, {"coplanar", {0, 255, 0}},
      {"curvature-open", {255, 128, 0}}, {"curvature-occluded", {0, 200, 255}}};
  int y = 14;
  for (const auto& [name, colour] : legend) {
    cv::line(img, {6, y - 4}, {26, y - 4}, colour, 2);
    cv::putText(img, name, {30, y}, cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1, cv::LINE_AA);
    y += 14;
  }
  return img;
}

}  // namespace clutterseg
