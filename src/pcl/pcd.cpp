#include "clutterseg/pcl/pcd.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "cloud.hpp"

namespace clutterseg {

namespace {

bool has_field(const pcl::PCLPointCloud2& cloud, const char* name) { return pcl::getFieldIndex(cloud, name) >= 0; }

// Least-squares line t = a * s + b over (s, t) sums.
struct LineFit {
  double n = 0, s = 0, t = 0, ss = 0, st = 0, tt = 0;
  void add(double si, double ti) {
    n += 1, s += si, t += ti, ss += si * si, st += si * ti, tt += ti * ti;
  }
  bool solve(double& a, double& b) const {
    const double det = n * ss - s * s;
    if (n < 3 || det <= 1e-9 * n * n) return false;
    a = (n * st - s * t) / det;
    b = (t - a * s) / n;
    return true;
  }
};

// fx, cx from x/z = u / fx - cx / fx over the valid pixels (and fy, cy likewise from y/z and v).
Camera fit_intrinsics(const pcl::PointCloud<pcl::PointXYZ>& cloud, const std::string& what) {
  LineFit fit_u, fit_v;
  for (int v = 0; v < static_cast<int>(cloud.height); ++v)
    for (int u = 0; u < static_cast<int>(cloud.width); ++u) {
      const auto& p = cloud.at(u, v);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || p.z <= 0) continue;
      fit_u.add(u, p.x / p.z);
      fit_v.add(v, p.y / p.z);
    }
  double au = 0, bu = 0, av = 0, bv = 0;
  if (!fit_u.solve(au, bu) || !fit_v.solve(av, bv) || au <= 0 || av <= 0)
    throw Error(what + ": cannot recover intrinsics (points do not span the image as a pinhole projection)");
  Camera cam;
  cam.fx = 1 / au;
  cam.cx = -bu / au;
  cam.fy = 1 / av;
  cam.cy = -bv / av;
  cam.width = static_cast<int>(cloud.width);
  cam.height = static_cast<int>(cloud.height);
  // A cloud that is not in the sensor frame (e.g. transformed to a robot base) has no such projection.
  double worst = 0;
  for (int v = 0; v < cam.height; v += 4)
    for (int u = 0; u < cam.width; u += 4) {
      const auto& p = cloud.at(u, v);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || p.z <= 0) continue;
      worst = std::max({worst, std::abs(cam.fx * p.x / p.z + cam.cx - u), std::abs(cam.fy * p.y / p.z + cam.cy - v)});
    }
  if (worst > 2.0)
    throw Error(what + ": points are not a pinhole projection of their pixels (off by up to " +
                std::to_string(static_cast<int>(worst)) + " px); give the intrinsics or a sensor-frame cloud");
  return cam;
}

// PCL's reader crashes on some malformed headers (e.g. a text file without one), so the header is checked
// first: FIELDS, SIZE and TYPE of equal length, WIDTH, HEIGHT and a DATA line within the first lines.
void check_header(const std::filesystem::path& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + ": cannot open");
  std::map<std::string, int> counts;
  std::string line;
  for (int i = 0; i < 64 && std::getline(in, line); ++i) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    std::string key, word;
    words >> key;
    int n = 0;
    while (words >> word) ++n;
    counts[key] = n;
    if (key == "DATA") break;
  }
  const bool complete = counts.count("FIELDS") && counts.count("SIZE") && counts.count("TYPE") &&
                        counts.count("WIDTH") && counts.count("HEIGHT") && counts.count("DATA");
  if (!complete || counts["FIELDS"] == 0 || counts["SIZE"] != counts["FIELDS"] || counts["TYPE"] != counts["FIELDS"])
    throw Error(what + ": not a PCD file (no valid header)");
}

}  // namespace

PcdFrame read_organized_pcd(const std::filesystem::path& path, const std::optional<Camera>& camera) {
  const std::string what = path.string();
  if (!std::filesystem::exists(path)) throw Error(what + ": no such file");
  if (std::filesystem::is_directory(path)) throw Error(what + ": is a folder, not a PCD file");

  check_header(path, what);
  pcl::PCLPointCloud2 blob;
  {
    baselines::QuietPcl quiet;
    pcl::PCDReader reader;
    if (reader.read(what, blob) < 0) throw Error(what + ": not a readable PCD file");
  }
  if (!has_field(blob, "x") || !has_field(blob, "y") || !has_field(blob, "z"))
    throw Error(what + ": PCD has no x/y/z fields");
  if (blob.height <= 1)
    throw Error(what + ": PCD is not organized (height " + std::to_string(blob.height) +
                "); an image-shaped cloud is needed");

  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  const int width = static_cast<int>(xyz.width), height = static_cast<int>(xyz.height);

  PcdFrame frame;
  frame.depth = cv::Mat(height, width, CV_32F, cv::Scalar(0));
  int valid = 0;
  for (int v = 0; v < height; ++v) {
    auto* row = frame.depth.ptr<float>(v);
    for (int u = 0; u < width; ++u) {
      const auto& p = xyz.at(u, v);
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && p.z > 0) {
        row[u] = p.z;
        ++valid;
      }
    }
  }
  if (valid == 0) throw Error(what + ": PCD holds no valid point (all NaN)");

  if (has_field(blob, "rgb") || has_field(blob, "rgba")) {
    pcl::PointCloud<pcl::PointXYZRGBA> colored;
    pcl::fromPCLPointCloud2(blob, colored);
    frame.color = cv::Mat(height, width, CV_8UC3);
    for (int v = 0; v < height; ++v) {
      auto* row = frame.color.ptr<cv::Vec3b>(v);
      for (int u = 0; u < width; ++u) {
        const auto& p = colored.at(u, v);
        row[u] = cv::Vec3b(p.b, p.g, p.r);
      }
    }
  }

  if (camera) {
    check_camera(*camera, width, height, what);
    frame.camera = *camera;
  } else {
    frame.camera = fit_intrinsics(xyz, what);
  }
  return frame;
}

}  // namespace clutterseg
