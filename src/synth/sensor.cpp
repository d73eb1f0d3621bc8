#include "clutterseg/synth/sensor.hpp"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "clutterseg/parallel.hpp"

namespace clutterseg::synth {

namespace {

using Eigen::Vector3d;

constexpr double kHalfPi = M_PI / 2;

double uniform01(std::uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

// Zero-mean, unit-variance noise from one hash: a sum of four 16-bit uniforms (Irwin-Hall), close
// enough to Gaussian once the field is smoothed, and much cheaper than Box-Muller per pixel.
float quick_normal(std::uint64_t h) {
  const double s = static_cast<double>(h & 0xffff) + static_cast<double>((h >> 16) & 0xffff) +
                   static_cast<double>((h >> 32) & 0xffff) + static_cast<double>(h >> 48);
  return static_cast<float>((s / 65536.0 - 2.0) * std::sqrt(3.0));
}

double box_muller(std::uint64_t h1, std::uint64_t h2) {
  const double u1 = std::max(uniform01(h1), 1e-300), u2 = uniform01(h2);
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * M_PI * u2);
}

// Random streams per pixel: one hash each.
enum Stream : std::uint64_t { kField = 1, kLateralU = 2, kLateralV = 3, kDropout = 4, kShadowEdge = 5 };
std::uint64_t pixel_hash(std::uint64_t seed, int index, Stream stream) {
  return mix_seed(seed, static_cast<std::uint64_t>(index) * 8 + stream);
}

// Unit-variance noise field with a Gaussian correlation of `sigma_px` pixels.
cv::Mat noise_field(int width, int height, double sigma_px, std::uint64_t seed) {
  cv::Mat field(height, width, CV_32F);
  parallel_for_rows(height, [&](int begin, int end) {
    for (int v = begin; v < end; ++v)
      for (int u = 0; u < width; ++u) field.at<float>(v, u) = quick_normal(pixel_hash(seed, v * width + u, kField));
  });
  if (sigma_px < 0.3) return field;
  const int ksize = 2 * static_cast<int>(std::ceil(3 * sigma_px)) + 1;
  const cv::Mat k = cv::getGaussianKernel(ksize, sigma_px, CV_64F);
  // Smoothing white noise with kernel w leaves variance sum(w^2); the 2D kernel is separable.
  const double sum_sq = k.dot(k);
  cv::Mat smooth;
  cv::sepFilter2D(field, smooth, CV_32F, k, k, cv::Point(-1, -1), 0, cv::BORDER_REFLECT);
  return smooth * (1.0 / sum_sq);
}

}  // namespace

std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

const char* to_string(Sensor sensor) {
  switch (sensor) {
    case Sensor::Ideal: return "ideal";
    case Sensor::KinectV1: return "kinect-v1";
    case Sensor::RealSenseD435: return "realsense-d435";
  }
  return "ideal";
}

std::vector<std::string> sensor_names() { return {"kinect-v1", "realsense-d435", "ideal"}; }

Sensor parse_sensor(const std::string& name) {
  for (Sensor s : {Sensor::Ideal, Sensor::KinectV1, Sensor::RealSenseD435})
    if (name == to_string(s)) return s;
  throw Error("--sensor " + name + ": unknown sensor (kinect-v1, realsense-d435 or ideal)");
}

SensorModel sensor_model(Sensor sensor, int image_width) {
  SensorModel m;
  m.sensor = sensor;
  const double scale = image_width / 640.0;
  switch (sensor) {
    case Sensor::Ideal: break;
    case Sensor::KinectV1:
      // Khoshelham & Elberink 2012: IR camera focal ~580 px at 640 px, baseline 7.5 cm, disparity in
      // 1/8 px. Nguyen, Izadi & Lovell 2012: axial and lateral noise (axial_sigma, lateral_sigma_px).
      m.baseline_m = 0.075;
      m.disparity_focal_px = 580.0 * scale;
      m.disparity_step_px = 0.125;
      m.min_depth_m = 0.5;
      m.max_depth_m = 4.0;
      m.lateral_px = 0.8 * scale;
      m.lateral_slope_px = 0.035 * scale;
      m.lateral_block_px = 3 * scale;
      m.shadow_grow_px = 2 * scale;
      m.grazing_start_deg = 75;
      m.grazing_end_deg = 88;
      m.correlation_px = 1.0 * scale;
      break;
    case Sensor::RealSenseD435:
      // Intel D400 datasheet: baseline 50 mm, depth HFOV 87 deg, RMS error = z^2 * subpixel / (f * b)
      // with subpixel 0.08; minimum depth ~0.28 m at full resolution.
      m.baseline_m = 0.050;
      m.disparity_focal_px = 0.5 * image_width / std::tan(87.0 / 2 * M_PI / 180);
      m.subpixel_rms_px = 0.08;
      m.min_depth_m = 0.28;
      m.max_depth_m = 10.0;
      m.stereo = true;
      m.lateral_px = 0.5 * scale;
      m.lateral_block_px = 2 * scale;
      m.grazing_start_deg = 75;
      m.grazing_end_deg = 88;
      m.correlation_px = 1.0 * scale;
      break;
  }
  return m;
}

double SensorModel::axial_sigma(double z, double theta) const {
  switch (sensor) {
    case Sensor::Ideal: return 0;
    case Sensor::KinectV1: {
      // Nguyen et al. 2012, Eq. for sigma_z(z, theta): 0.0012 + 0.0019 (z - 0.4)^2 + 0.0001/sqrt(z) *
      // theta^2 / (pi/2 - theta)^2 [m].
      const double th = std::clamp(theta, 0.0, 85.0 * M_PI / 180);
      return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) + 0.0001 / std::sqrt(z) * th * th / ((kHalfPi - th) * (kHalfPi - th));
    }
    case Sensor::RealSenseD435: return z * z * subpixel_rms_px / (disparity_focal_px * baseline_m);
  }
  return 0;
}

double SensorModel::depth_step(double z) const {
  if (disparity_step_px <= 0 || disparity_focal_px <= 0) return 0;
  return z * z * disparity_step_px / (disparity_focal_px * baseline_m);
}

double SensorModel::lateral_sigma_px(double theta) const {
  const double th = std::clamp(theta, 0.0, 85.0 * M_PI / 180);
  return lateral_px + lateral_slope_px * th / (kHalfPi - th);
}

SensorFrame simulate(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& world_to_camera,
                     const SensorModel& model, std::uint64_t seed) {
  const int W = camera.width, H = camera.height, N = W * H;
  SensorFrame out;
  out.labels = cv::Mat(H, W, CV_32S, cv::Scalar(0));
  out.true_depth = cv::Mat(H, W, CV_32F, cv::Scalar(0));
  out.color = cv::Mat(H, W, CV_8UC3, cv::Scalar::all(0));
  out.shadow = cv::Mat(H, W, CV_8U, cv::Scalar(0));
  const bool ideal = model.sensor == Sensor::Ideal;

  // 1. Exact geometry seen by the camera, and whether the projector (or the right imager) sees it too.
  const RayCaster camera_view(scene, camera, world_to_camera);
  const Vector3d second(model.baseline_m, 0, 0);
  // Points seen by the camera appear shifted by f * b / z in the second view: tile a margin for them.
  const int margin = ideal ? 0 : static_cast<int>(std::ceil(camera.fx * model.baseline_m / 0.2)) + 16;
  const RayCaster second_view(scene, camera, world_to_camera, second, margin);
  std::vector<float> incidence(static_cast<size_t>(N), 0.f);  // angle to camera or projector, the larger [rad]
  std::vector<int> shape_of(static_cast<size_t>(N), -1);
  parallel_for_rows(H, [&](int begin, int end) {
    for (int v = begin; v < end; ++v)
      for (int u = 0; u < W; ++u) {
        const Vector3d dir = camera_view.pixel_ray(u, v);
        double t = 0;
        Vector3d n;
        const int hit = camera_view.cast(dir, u, v, 1e3, t, n);
        if (hit < 0) continue;
        const int i = v * W + u;
        const Shape& s = scene.shapes[static_cast<size_t>(hit)];
        if (n.dot(dir) > 0) n = -n;
        const Vector3d p = t * dir;
        shape_of[static_cast<size_t>(i)] = hit;
        out.labels.at<int>(v, u) = s.label;
        out.true_depth.at<float>(v, u) = static_cast<float>(p.z());
        const double cos_cam = -n.dot(dir);
        const double shade = 0.3 + 0.7 * std::max(0.0, cos_cam);
        out.color.at<cv::Vec3b>(v, u) = cv::Vec3b(cv::saturate_cast<uchar>(s.color[0] * shade),
                                                  cv::saturate_cast<uchar>(s.color[1] * shade),
                                                  cv::saturate_cast<uchar>(s.color[2] * shade));
        double cos_in = cos_cam;
        if (!ideal) {
          // Shadow: the straight line from the second viewpoint to the point is blocked (ray casting,
          // not a heuristic), the surface faces away from it, or (stereo) it is outside its image.
          const Vector3d w = p - second;
          const double dist = w.norm();
          const Vector3d dir2 = w / dist;
          const double cos_second = -n.dot(dir2);
          const double u2 = camera.cx + camera.fx * w.x() / w.z(), v2 = camera.cy + camera.fy * w.y() / w.z();
          bool shadowed = cos_second <= 0;
          if (model.stereo && (u2 < -0.5 || u2 > W - 0.5 || v2 < -0.5 || v2 > H - 0.5)) shadowed = true;
          if (!shadowed) {
            double t2 = 0;
            Vector3d n2;
            // A convex shape cannot hide its own surface where it faces the second view.
            shadowed = second_view.cast(dir2, u2, v2, dist - 1e-6 * (1 + dist), t2, n2, is_convex(s) ? hit : -1) >= 0;
          }
          if (shadowed) out.shadow.at<uchar>(v, u) = 255;
          cos_in = std::min(cos_in, cos_second);
        }
        incidence[static_cast<size_t>(i)] = std::acos(std::clamp(static_cast<float>(cos_in), 0.f, 1.f));
      }
  });

  out.depth = cv::Mat(H, W, CV_32F, cv::Scalar(0));
  if (ideal) {
    out.true_depth.copyTo(out.depth);
  } else {
    // 2. Lateral noise: near a change of surface or of shadow, a pixel reports the depth of a
    // neighbour displaced by N(0, sigma_L) pixels (Nguyen et al. 2012), so edges and shadow borders fray.
    cv::Mat surface_id(H, W, CV_32F);
    for (int i = 0; i < N; ++i)
      surface_id.at<float>(i) = (shape_of[static_cast<size_t>(i)] < 0 || out.shadow.at<uchar>(i)) ? 0.f : float(shape_of[static_cast<size_t>(i)] + 1);
    cv::Mat id_max, id_min;
    const cv::Mat window = cv::Mat::ones(5, 5, CV_8U);
    cv::dilate(surface_id, id_max, window);
    cv::erode(surface_id, id_min, window);
    const cv::Mat field = noise_field(W, H, model.correlation_px, mix_seed(seed, 11));
    // Pixels beside a shadow: the matching window reaches into it, and half of them fail too.
    cv::Mat near_shadow;
    const int grow = static_cast<int>(std::lround(model.shadow_grow_px));
    if (grow > 0) cv::dilate(out.shadow, near_shadow, cv::Mat::ones(1, 2 * grow + 1, CV_8U));
    const double F = model.disparity_focal_px * model.baseline_m;  // disparity [px] = F / z
    const int lateral_block = std::max(1, static_cast<int>(std::lround(model.lateral_block_px)));
    const double grazing0 = model.grazing_start_deg * M_PI / 180, grazing1 = model.grazing_end_deg * M_PI / 180;
    parallel_for_rows(H, [&](int begin, int end) {
      for (int v = begin; v < end; ++v)
        for (int u = 0; u < W; ++u) {
          const int i = v * W + u;
          int src = i;
          if (id_max.at<float>(i) != id_min.at<float>(i)) {
            // One offset per block of pixels: real edges fray in blocks (the matching window), not per pixel.
            const int block = (v / lateral_block) * W + u / lateral_block;
            const double sigma = model.lateral_sigma_px(incidence[static_cast<size_t>(i)]);
            const int du = static_cast<int>(std::lround(std::clamp(sigma * box_muller(pixel_hash(seed, block, kLateralU), pixel_hash(seed, block, kLateralV)), -2.0, 2.0)));
            const int dv = static_cast<int>(std::lround(std::clamp(sigma * box_muller(pixel_hash(seed, block, kLateralV), pixel_hash(seed, block, kLateralU)), -2.0, 2.0)));
            src = std::clamp(v + dv, 0, H - 1) * W + std::clamp(u + du, 0, W - 1);
          }
          const float z_true = out.true_depth.at<float>(src);
          if (z_true <= 0 || out.shadow.at<uchar>(src)) continue;
          if (grow > 0 && near_shadow.at<uchar>(src) && uniform01(pixel_hash(seed, i, kShadowEdge)) < 0.5) continue;
          // Dropouts at grazing angles to the camera or the projector.
          const double theta = incidence[static_cast<size_t>(src)];
          if (theta > grazing0) {
            const double p_drop = grazing1 > grazing0 ? (theta - grazing0) / (grazing1 - grazing0) : 1.0;
            if (uniform01(pixel_hash(seed, i, kDropout)) < p_drop) continue;
          }
          // Axial noise and quantisation, both in disparity, so that steps and noise grow with z^2.
          const double z = z_true;
          double disparity = F / z;
          if (model.disparity_step_px > 0) {
            // Nguyen's sigma already contains the quantisation: add only the rest as noise.
            const double sigma = model.axial_sigma(z, theta), step = model.depth_step(z);
            const double sigma_noise = std::sqrt(std::max(sigma * sigma - step * step / 12, 0.0625 * sigma * sigma));
            disparity += sigma_noise * F / (z * z) * field.at<float>(i);
            disparity = std::round(disparity / model.disparity_step_px) * model.disparity_step_px;
          } else {
            disparity += model.subpixel_rms_px * field.at<float>(i);
          }
          if (disparity <= 0) continue;
          const double z_out = F / disparity;
          if (z_out < model.min_depth_m || z_out > model.max_depth_m) continue;
          out.depth.at<float>(i) = static_cast<float>(z_out);
        }
    });
  }
  // Millimetres; depths beyond the 16-bit range are no measurement.
  out.depth_mm = cv::Mat(H, W, CV_16U, cv::Scalar(0));
  for (int i = 0; i < N; ++i) {
    const double mm = std::round(out.depth.at<float>(i) * 1000.0);
    if (mm >= 1 && mm <= 65535) out.depth_mm.at<std::uint16_t>(i) = static_cast<std::uint16_t>(mm);
  }
  return out;
}

}  // namespace clutterseg::synth
