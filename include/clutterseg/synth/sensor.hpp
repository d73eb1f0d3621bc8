// Depth-sensor models for synthetic scenes: what a Kinect v1 or a RealSense D435 would report for a
// ray-cast scene (quantisation, axial and lateral noise, projector/stereo shadows, grazing-angle dropouts,
// range limits), with the exact labels beside it. Numbers and sources: docs/SYNTH.md.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "clutterseg/synth/scene.hpp"

namespace clutterseg::synth {

enum class Sensor { Ideal, KinectV1, RealSenseD435 };

// "ideal", "kinect-v1", "realsense-d435"; parse_sensor throws Error for anything else.
const char* to_string(Sensor sensor);
Sensor parse_sensor(const std::string& name);
std::vector<std::string> sensor_names();

struct SensorModel {
  Sensor sensor = Sensor::Ideal;
  double baseline_m = 0;          // projector (Kinect) or right imager (D435) along +x of the depth camera [m]
  double disparity_focal_px = 0;  // focal length of the disparity measurement at this image width [px]
  double disparity_step_px = 0;   // disparity quantisation [px]; 0 = none
  double subpixel_rms_px = 0;     // disparity noise [px] where the model is given in disparity (D435)
  double min_depth_m = 0, max_depth_m = 65.0;  // nothing is reported outside [m]
  bool stereo = false;            // the second view is a camera: it must also see the point in its image
  double lateral_px = 0;          // lateral noise at depth edges, at normal incidence [px at this width]
  double lateral_slope_px = 0;    // ... growing by this times theta / (pi/2 - theta) [px]
  double lateral_block_px = 1;    // pixels in a square block share one lateral offset [px]
  double shadow_grow_px = 0;      // pixels this close (along rows) to a shadow drop out with p = 0.5 [px]
  double grazing_start_deg = 90;  // dropouts start at this incidence angle to camera or projector [deg]
  double grazing_end_deg = 90;    // ... and every pixel is missing from this angle on [deg]
  double correlation_px = 0;      // Gaussian correlation length of the noise field [px at this width]

  // Total standard deviation of reported depth at camera depth z [m] and incidence angle theta [rad],
  // quantisation included (what a flat patch measures).
  double axial_sigma(double z, double theta) const;
  // Depth step of the quantised disparity at z [m] (0 without quantisation).
  double depth_step(double z) const;
  double lateral_sigma_px(double theta) const;
};

// The model of `sensor` for images `image_width` pixels wide (pixel quantities scale with the width).
SensorModel sensor_model(Sensor sensor, int image_width);

struct SensorFrame {
  cv::Mat depth;       // CV_32F metres as the sensor reports them (before rounding to mm), 0 = none
  cv::Mat depth_mm;    // CV_16U millimetres, 0 = none
  cv::Mat labels;      // CV_32S exact visible shape label per pixel (0 = table and background)
  cv::Mat color;       // CV_8UC3 BGR plain Lambertian shading of the exact geometry
  cv::Mat true_depth;  // CV_32F exact camera z [m], 0 = nothing hit
  cv::Mat shadow;      // CV_8U 255 where the projector (or right imager) cannot see the surface
};

// Renders `scene` through `camera` and applies the sensor model; every random draw is a function of
// `seed` and the pixel, so the output does not depend on the thread count.
SensorFrame simulate(const Scene& scene, const Camera& camera, const Eigen::Isometry3d& world_to_camera,
                     const SensorModel& model, std::uint64_t seed);

// A 64-bit mix of a seed and a stream number (splitmix64), for seeding per frame or per pixel.
std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream);

}  // namespace clutterseg::synth
