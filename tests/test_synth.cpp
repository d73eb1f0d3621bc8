// clutterseg synth: exact geometry, the sensor models and the scene presets.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <set>

#include "clutterseg/synth/dataset.hpp"
#include "scenes.hpp"

using namespace clutterseg;
using namespace clutterseg::synth;
using Eigen::Vector3d;

namespace {

// Signed distance to a shape, written independently of the ray caster (negative inside).
double box_sdf(const Vector3d& p, const Vector3d& half) {
  const Vector3d q = p.cwiseAbs() - half;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}
double cylinder_sdf(const Vector3d& p, double r, double zlo, double zhi) {
  const double dr = std::hypot(p.x(), p.y()) - r, dz = std::max(zlo - p.z(), p.z() - zhi);
  return std::hypot(std::max(dr, 0.0), std::max(dz, 0.0)) + std::min(std::max(dr, dz), 0.0);
}
double sdf(const Shape& s, const Vector3d& world) {
  const Vector3d p = s.pose.inverse() * world;
  const double r = s.size.x(), h = s.size.z();
  switch (s.type) {
    case ShapeType::Plane: {
      const Vector3d half(s.size.x() > 0 ? s.size.x() : 1e9, s.size.y() > 0 ? s.size.y() : 1e9, 0);
      return box_sdf(p, half);
    }
    case ShapeType::Box: return box_sdf(p, s.size);
    case ShapeType::Sphere: return p.norm() - r;
    case ShapeType::Cylinder: return cylinder_sdf(p, r, -h, h);
    case ShapeType::Cup: return std::max(cylinder_sdf(p, r, -h, h), -cylinder_sdf(p, r - s.wall, -h + s.wall, h + 1));
    case ShapeType::Bowl: {
      const Vector3d c = p - Vector3d(0, 0, h);  // sphere centre on the rim
      const double solid = std::max({c.norm() - r, c.z(), -2 * h - c.z()});
      const double cavity = std::max(c.norm() - (r - s.wall), -2 * h + s.wall - c.z());
      return std::max(solid, -cavity);
    }
  }
  return 1e9;
}

// First surface along a ray by sphere tracing the distance functions: an independent ray caster.
int trace(const Scene& scene, const Vector3d& origin, const Vector3d& dir, double& t_hit) {
  double t = 0;
  for (int step = 0; step < 400 && t < 20; ++step) {
    const Vector3d p = origin + t * dir;
    double best = 1e9;
    int which = -1;
    for (size_t i = 0; i < scene.shapes.size(); ++i) {
      const double d = sdf(scene.shapes[i], p);
      if (d < best) { best = d; which = static_cast<int>(i); }
    }
    if (best < 1e-6) { t_hit = t; return which; }
    t += std::max(best, 1e-6);
  }
  return -1;
}

Camera small_camera() { return default_camera(160, 120); }

}  // namespace

TEST(SynthGeometry, LabelsAndDepthAgreeWithAnIndependentTracerOnEveryPreset) {
  const Camera cam = small_camera();
  for (const auto& preset : presets()) {
    const SynthFrame f = synthesize(preset.name, 7, 1, cam, Sensor::Ideal);
    const Eigen::Isometry3d cam_to_world = f.scene.world_to_camera.inverse();
    int mismatched = 0, labelled = 0;
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
        const int label = f.sensor.labels.at<int>(v, u);
        const float z = f.sensor.depth.at<float>(v, u);
        if (label > 0) {
          ++labelled;
          // Every labelled pixel's depth lies on its own object's surface...
          const Vector3d world = cam_to_world * (z * ray);
          const Shape& own = f.scene.scene.shapes[static_cast<size_t>(f.scene.objects[static_cast<size_t>(label - 1)].shape)];
          ASSERT_NEAR(sdf(own, world), 0.0, 5e-5) << preset.name << " pixel " << u << "," << v;
          // ... and inside no other shape.
          for (const Shape& other : f.scene.scene.shapes)
            if (&other != &own) ASSERT_GT(sdf(other, world), -5e-5) << preset.name;
        }
        double t = 0;
        const int shape = trace(f.scene.scene, f.scene.eye, (cam_to_world.linear() * ray).normalized(), t);
        const int traced = shape < 0 ? 0 : f.scene.scene.shapes[static_cast<size_t>(shape)].label;
        if (traced != label) ++mismatched;
      }
    EXPECT_GT(labelled, 0) << preset.name;
    // Sphere tracing stalls on a few grazing silhouette rays; everything else must agree.
    EXPECT_LE(mismatched, cam.width * cam.height / 500) << preset.name;
  }
}

TEST(SynthGeometry, BowlAndCupShowTheirInnerWall) {
  Scene scene;
  scene.shapes.push_back(scenes::table());
  Shape bowl;
  bowl.type = ShapeType::Bowl;
  bowl.size = {0.08, 0.08, 0.025};
  bowl.pose = Eigen::Translation3d(0, 0, 0.025) * Eigen::Isometry3d::Identity();
  bowl.label = 1;
  scene.shapes.push_back(bowl);
  // Looking straight down into the bowl: the centre ray meets the inner floor, one wall above the foot.
  double t = 0;
  Vector3d n;
  ASSERT_TRUE(intersect(bowl, {0, 0, 1}, {0, 0, -1}, t, n));
  EXPECT_NEAR(1 - t, 0.005, 1e-9);
  EXPECT_NEAR(n.z(), 1, 1e-9);
  // A ray at 0.06 m from the axis meets the concave inner sphere (normal pointing to the centre).
  ASSERT_TRUE(intersect(bowl, {0.06, 0, 1}, {0, 0, -1}, t, n));
  const double ri = 0.075, z_inner = 0.05 - std::sqrt(ri * ri - 0.06 * 0.06);
  EXPECT_NEAR(1 - t, z_inner, 1e-9);
  EXPECT_LT(n.x(), 0);
  // From the side, below the rim, the convex outer wall.
  ASSERT_TRUE(intersect(bowl, {-1, 0, 0.04}, {1, 0, 0}, t, n));
  EXPECT_NEAR(-1 + t, -std::sqrt(0.08 * 0.08 - 0.01 * 0.01), 1e-9);
  EXPECT_LT(n.x(), 0);
}

namespace {

// A flat table seen straight down from `z` metres; returns the RMS depth error on the central patch.
double flat_rms(Sensor sensor, double z, double& model_sigma, int& valid) {
  Scene scene;
  scene.shapes.push_back(scenes::table(5));
  const Camera cam = default_camera(640, 480);
  const Eigen::Isometry3d w2c = look_at({0, 0, z}, {0, 0, 0});
  const SensorModel model = sensor_model(sensor, cam.width);
  const SensorFrame f = simulate(scene, cam, w2c, model, 42);
  double sum = 0;
  valid = 0;
  for (int v = 140; v < 340; ++v)
    for (int u = 220; u < 420; ++u) {
      const float d = f.depth.at<float>(v, u);
      if (d <= 0) continue;
      sum += (d - z) * (d - z);
      ++valid;
    }
  model_sigma = model.axial_sigma(z, 0);
  return std::sqrt(sum / std::max(valid, 1));
}

}  // namespace

TEST(SynthSensor, KinectNoiseOnAFlatTableMatchesNguyenSigma) {
  for (double z : {0.8, 1.2, 2.0, 3.0}) {
    double sigma = 0;
    int valid = 0;
    const double rms = flat_rms(Sensor::KinectV1, z, sigma, valid);
    EXPECT_EQ(valid, 200 * 200) << z;
    EXPECT_NEAR(rms / sigma, 1.0, 0.12) << "z " << z << " rms " << rms << " model " << sigma;
  }
  // The model itself: 0.0012 + 0.0019 (z - 0.4)^2 at normal incidence (Nguyen et al. 2012).
  EXPECT_NEAR(sensor_model(Sensor::KinectV1, 640).axial_sigma(1.0, 0), 0.0012 + 0.0019 * 0.36, 1e-12);
}

TEST(SynthSensor, RealSenseNoiseFollowsIntelRmsFormula) {
  const SensorModel m = sensor_model(Sensor::RealSenseD435, 640);
  for (double z : {0.5, 1.0, 2.0}) {
    double sigma = 0;
    int valid = 0;
    const double rms = flat_rms(Sensor::RealSenseD435, z, sigma, valid);
    EXPECT_NEAR(sigma, z * z * 0.08 / (m.disparity_focal_px * 0.05), 1e-12);
    EXPECT_NEAR(rms / sigma, 1.0, 0.12) << "z " << z;
  }
  // About 1 % of the distance at 2 m, within the datasheet's "< 2 % at 2 m".
  EXPECT_LT(m.axial_sigma(2.0, 0) / 2.0, 0.02);
}

TEST(SynthSensor, IdealSensorIsExact) {
  double sigma = 0;
  int valid = 0;
  EXPECT_LT(flat_rms(Sensor::Ideal, 1.3, sigma, valid), 1e-6);
  EXPECT_EQ(valid, 200 * 200);
}

TEST(SynthSensor, KinectDisparityIsQuantisedInEighthPixelsSoStepsGrowWithZSquared) {
  // A table seen obliquely: depth from about 0.7 m to beyond 2 m.
  Scene scene;
  scene.shapes.push_back(scenes::table(5));
  const Camera cam = default_camera(640, 480);
  const SensorModel model = sensor_model(Sensor::KinectV1, cam.width);
  const SensorFrame f = simulate(scene, cam, look_at({0, -1.2, 0.7}, {0, 0, 0}), model, 3);
  const double F = model.disparity_focal_px * model.baseline_m;
  std::set<float> values;
  int checked = 0;
  for (int i = 0; i < f.depth.rows * f.depth.cols; ++i) {
    const float z = f.depth.at<float>(i);
    if (z <= 0) continue;
    const double eighths = 8 * F / z;
    ASSERT_NEAR(eighths, std::round(eighths), 2e-3 * eighths / 300);
    values.insert(z);
    ++checked;
  }
  ASSERT_GT(checked, 100000);
  // Consecutive reported depths near 1 m and 2 m are one disparity step apart: z^2 / (8 F).
  for (double z : {1.0, 2.0}) {
    const auto it = values.lower_bound(static_cast<float>(z));
    ASSERT_NE(it, values.end());
    ASSERT_NE(std::next(it), values.end());
    const double step = *std::next(it) - *it;
    EXPECT_NEAR(step, model.depth_step(*it), 0.05 * model.depth_step(*it)) << z;
  }
  EXPECT_NEAR(model.depth_step(1.0), 1.0 / (8 * 580 * 0.075), 1e-12);  // 2.9 mm at 1 m
  EXPECT_NEAR(model.depth_step(2.0) / model.depth_step(1.0), 4.0, 1e-9);
}

TEST(SynthSensor, ProjectorShadowIsABandLeftOfTheBoxOfTheRightWidth) {
  // Camera 1 m above the table looking straight down; a 10 cm tall box whose left face is at x = -5 cm.
  Scene scene;
  scene.shapes.push_back(scenes::table(5));
  scene.shapes.push_back(scenes::box(1, {0.0, 0, 0.05}, {0.05, 0.05, 0.05}));
  const Camera cam = default_camera(640, 480);
  const Eigen::Isometry3d w2c = look_at({0, 0, 1}, {0, 0, 0});
  const SensorModel kinect = sensor_model(Sensor::KinectV1, cam.width);
  const SensorFrame f = simulate(scene, cam, w2c, kinect, 5);
  // The box's image columns on the centre row, and the shadow on each side of it.
  const int row = 240;
  int first = -1, last = -1;
  for (int u = 0; u < cam.width; ++u)
    if (f.labels.at<int>(row, u) == 1) { if (first < 0) first = u; last = u; }
  ASSERT_GT(first, 0);
  int left = 0, right = 0;
  for (int u = 0; u < first; ++u) left += f.shadow.at<uchar>(row, u) > 0;
  for (int u = last + 1; u < cam.width; ++u) right += f.shadow.at<uchar>(row, u) > 0;
  // Similar triangles with the projector 7.5 cm to the right: the table is shadowed from
  // x = b + (x_e - b) / 0.9 to where the camera stops seeing it, x_e / 0.9 (x_e = -5 cm, top at 0.9 m).
  const double b = 0.075, x_e = -0.05;
  const double expected_px = cam.fx * ((x_e / 0.9) - (b + (x_e - b) / 0.9));
  EXPECT_NEAR(left, expected_px, 1.5);
  EXPECT_EQ(right, 0);
  // Nothing is missing in the ideal rendering.
  const SensorFrame ideal = simulate(scene, cam, w2c, sensor_model(Sensor::Ideal, cam.width), 5);
  EXPECT_EQ(cv::countNonZero(ideal.depth == 0), 0);
  EXPECT_EQ(cv::countNonZero(ideal.shadow), 0);
}

TEST(SynthSensor, NothingOutsideTheKinectRange) {
  double sigma = 0;
  int valid = 0;
  flat_rms(Sensor::KinectV1, 0.45, sigma, valid);
  EXPECT_EQ(valid, 0);
  flat_rms(Sensor::KinectV1, 4.3, sigma, valid);
  EXPECT_EQ(valid, 0);
}

TEST(SynthSensor, GrazingSurfacesDropOut) {
  // A table seen at 84 degrees incidence is mostly missing; at 30 degrees it is complete.
  Scene scene;
  scene.shapes.push_back(scenes::table(20));
  const Camera cam = default_camera(160, 120);
  const SensorModel kinect = sensor_model(Sensor::KinectV1, cam.width);
  auto valid_share = [&](double elevation_deg) {
    const double e = elevation_deg * M_PI / 180;
    const SensorFrame f = simulate(scene, cam, look_at({0, -1.5 * std::cos(e), 1.5 * std::sin(e)}, {0, 0, 0}), kinect, 9);
    const cv::Rect centre(60, 45, 40, 30);
    return cv::countNonZero(f.depth(centre) > 0) / double(centre.area());
  };
  EXPECT_GT(valid_share(60), 0.99);
  EXPECT_LT(valid_share(6), 0.7);
}

namespace {

bool resting(const ObjectInfo& o, const GeneratedScene& g) {
  const double bottom = o.pose.translation().z() - o.size.z() / 2;
  if (std::abs(bottom) < 1e-9) return true;
  // Else on top of another object: the point just below its centre is inside that object.
  const Vector3d below(o.pose.translation().x(), o.pose.translation().y(), bottom - 1e-4);
  for (const auto& other : g.objects)
    if (other.id != o.id && sdf(g.scene.shapes[static_cast<size_t>(other.shape)], below) < 0 &&
        std::abs(other.pose.translation().z() + other.size.z() / 2 - bottom) < 1e-9)
      return true;
  return false;
}

}  // namespace

TEST(SynthScenes, PresetsHoldThePromisedObjectsRestingWithoutInterpenetration) {
  const Camera cam = default_camera(320, 240);
  for (const auto& preset : presets()) {
    for (int frame = 0; frame < 6; ++frame) {
      const GeneratedScene g = generate_scene(preset.name, 11, frame, cam);
      const int n = static_cast<int>(g.objects.size());
      EXPECT_GE(n, preset.min_objects) << preset.name << " frame " << frame;
      EXPECT_LE(n, preset.max_objects) << preset.name << " frame " << frame;
      EXPECT_EQ(g.family, preset.name);
      for (int i = 0; i < n; ++i) {
        const ObjectInfo& o = g.objects[static_cast<size_t>(i)];
        EXPECT_EQ(o.id, i + 1);
        EXPECT_EQ(g.scene.shapes[static_cast<size_t>(o.shape)].label, o.id);
        EXPECT_TRUE(resting(o, g)) << preset.name << " frame " << frame << " object " << o.id << " floats";
      }
      // No object reaches more than 0.5 mm into another: sample each one's inside on a grid.
      for (const auto& a : g.objects) {
        const Shape& sa = g.scene.shapes[static_cast<size_t>(a.shape)];
        for (int k = 0; k < 1000; ++k) {
          const Vector3d local((k % 10 + 0.5) / 10 - 0.5, (k / 10 % 10 + 0.5) / 10 - 0.5, (k / 100 + 0.5) / 10 - 0.5);
          const Vector3d p = a.pose * local.cwiseProduct(a.size);
          if (sdf(sa, p) > -5e-4) continue;
          for (const auto& b : g.objects)
            if (b.id != a.id)
              ASSERT_GT(sdf(g.scene.shapes[static_cast<size_t>(b.shape)], p), -5e-4)
                  << preset.name << " frame " << frame << ": objects " << a.id << " and " << b.id << " interpenetrate";
        }
      }
      // The camera: 0.5-1.5 m from its target, looking down at 30-70 degrees.
      const Vector3d view = g.target - g.eye;
      EXPECT_GE(view.norm(), 0.5 - 1e-9);
      EXPECT_LE(view.norm(), 1.5 + 1e-9);
      const double down = std::asin(-view.z() / view.norm()) * 180 / M_PI;
      EXPECT_GE(down, 30 - 1e-6);
      EXPECT_LE(down, 70 + 1e-6);
    }
  }
}

TEST(SynthScenes, StackedBoxesStackAndOccludedBoxIsSplitInTwo) {
  const Camera cam = default_camera(320, 240);
  int split = 0;
  for (int frame = 0; frame < 10; ++frame) {
    const GeneratedScene stacked = generate_scene("stacked-boxes", 2, frame, cam);
    EXPECT_TRUE(std::any_of(stacked.objects.begin(), stacked.objects.end(),
                            [](const ObjectInfo& o) { return o.pose.translation().z() - o.size.z() / 2 > 0.01; }));
    const SynthFrame f = synthesize("occluded-box", 2, frame, cam, Sensor::Ideal);
    cv::Mat back = f.sensor.labels == 1, components;
    if (cv::connectedComponents(back, components, 8) - 1 >= 2) ++split;
  }
  EXPECT_GE(split, 8) << "the occluder must cut the box in two in most frames";
}

TEST(SynthScenes, SequenceKeepsTheCameraAndMovesOneObject) {
  const Camera cam = default_camera(320, 240);
  const GeneratedScene a = generate_scene("sequence", 4, 10, cam), b = generate_scene("sequence", 4, 11, cam);
  EXPECT_TRUE(a.world_to_camera.isApprox(b.world_to_camera));
  ASSERT_EQ(a.objects.size(), 4u);
  for (size_t i = 0; i + 1 < a.objects.size(); ++i) EXPECT_TRUE(a.objects[i].pose.isApprox(b.objects[i].pose));
  const double moved = (a.objects.back().pose.translation() - b.objects.back().pose.translation()).norm();
  EXPECT_GT(moved, 0.001);
  EXPECT_LT(moved, 0.02);
}

TEST(SynthScenes, UnknownPresetAndSensorNameTheValue) {
  EXPECT_THROW(generate_scene("nope", 1, 0, small_camera()), Error);
  try {
    parse_sensor("kinect-v3");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("kinect-v3"), std::string::npos);
  }
}
