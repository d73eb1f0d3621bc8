// Organized PCD input: intrinsics recovered from real clouds, NaN as no measurement, clear errors.
#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <unistd.h>

#include "clutterseg/pcl/pcd.hpp"

namespace fs = std::filesystem;
using clutterseg::Camera;
using clutterseg::Error;
using clutterseg::read_organized_pcd;

namespace {

const fs::path kPcdDir = fs::path(CLUTTERSEG_DATA_DIR) / "pcl-organized";

fs::path temp_file(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("clutterseg_test_pcd_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

// The message of the Error thrown by f, or "" when none is thrown.
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

// An organized cloud of a tilted plane seen by a known camera; NaN in the top-left corner.
pcl::PointCloud<pcl::PointXYZRGBA> plane_cloud(const Camera& cam) {
  pcl::PointCloud<pcl::PointXYZRGBA> cloud(cam.width, cam.height);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      auto& p = cloud.at(u, v);
      const float z = 1.0f + 0.002f * v;
      if (u < 10 && v < 10) {
        p.x = p.y = p.z = std::numeric_limits<float>::quiet_NaN();
      } else {
        p.x = static_cast<float>((u - cam.cx) * z / cam.fx);
        p.y = static_cast<float>((v - cam.cy) * z / cam.fy);
        p.z = z;
      }
      p.r = 200, p.g = 100, p.b = 50, p.a = 255;
    }
  cloud.is_dense = false;
  return cloud;
}

Camera small_camera() {
  Camera cam;
  cam.fx = 300, cam.fy = 310, cam.cx = 79.5, cam.cy = 61.0, cam.width = 160, cam.height = 120;
  return cam;
}

}  // namespace

TEST(Pcd, KinectCloudGivesKinectIntrinsicsAndNanAsNoMeasurement) {
  const fs::path file = kPcdDir / "milk_cartoon_all_small_clorox.pcd";
  if (!fs::exists(file)) GTEST_SKIP() << file << " missing";
  const auto frame = read_organized_pcd(file);
  EXPECT_EQ(frame.depth.cols, 640);
  EXPECT_EQ(frame.depth.rows, 480);
  EXPECT_EQ(frame.depth.type(), CV_32F);
  EXPECT_NEAR(frame.camera.fx, 525, 10);
  EXPECT_NEAR(frame.camera.fy, 525, 10);
  EXPECT_NEAR(frame.camera.cx, 319.5, 10);
  EXPECT_NEAR(frame.camera.cy, 239.5, 10);
  const int valid = cv::countNonZero(frame.depth);
  EXPECT_GT(valid, 100000);
  EXPECT_LT(valid, 640 * 480);  // the file has NaN points; they become 0
  ASSERT_EQ(frame.color.type(), CV_8UC3);
  EXPECT_GT(cv::norm(frame.color, cv::NORM_L1), 0);
}

TEST(Pcd, ConsecutiveKinectFramesAgreeOnIntrinsics) {
  for (const char* name : {"frame_20121214T142255.814212.pcd", "frame_20121214T142256.332395.pcd"}) {
    const fs::path file = kPcdDir / name;
    if (!fs::exists(file)) GTEST_SKIP() << file << " missing";
    EXPECT_NEAR(read_organized_pcd(file).camera.fx, 525, 10) << name;
  }
}

TEST(Pcd, StereoCloudGivesItsOwnFocalLength) {
  const fs::path file = kPcdDir / "table_scene_mug_stereo_textured.pcd";
  if (!fs::exists(file)) GTEST_SKIP() << file << " missing";
  const auto frame = read_organized_pcd(file);
  EXPECT_NEAR(frame.camera.fx, 964, 15);
  EXPECT_NEAR(frame.camera.fy, 964, 15);
}

TEST(Pcd, RecoversExactIntrinsicsAndDepthOfABinaryCompressedCloud) {
  const Camera cam = small_camera();
  const fs::path file = temp_file("plane.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(file.string(), plane_cloud(cam)), 0);
  const auto frame = read_organized_pcd(file);
  EXPECT_NEAR(frame.camera.fx, cam.fx, 0.01);
  EXPECT_NEAR(frame.camera.fy, cam.fy, 0.01);
  EXPECT_NEAR(frame.camera.cx, cam.cx, 0.01);
  EXPECT_NEAR(frame.camera.cy, cam.cy, 0.01);
  EXPECT_EQ(frame.depth.at<float>(0, 0), 0.0f);                // NaN = no measurement
  EXPECT_NEAR(frame.depth.at<float>(50, 20), 1.1f, 1e-6);      // z of row 50
  EXPECT_EQ(frame.color.at<cv::Vec3b>(50, 20), cv::Vec3b(50, 100, 200));  // BGR
}

TEST(Pcd, GivenIntrinsicsAreUsedAndMustFitTheCloud) {
  const Camera cam = small_camera();
  const fs::path file = temp_file("given.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(file.string(), plane_cloud(cam)), 0);
  Camera given = cam;
  given.fx = 123;
  EXPECT_EQ(read_organized_pcd(file, given).camera.fx, 123);
  given.width = 640;
  given.height = 480;
  EXPECT_NE(error_of([&] { read_organized_pcd(file, given); }).find(file.string()), std::string::npos);
}

TEST(Pcd, UnorganizedCloudIsAOneLineErrorNamingTheFile) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 50; ++i) cloud.push_back(pcl::PointXYZ(0.01f * i, 0.0f, 1.0f));
  const fs::path file = temp_file("unorganized.pcd");
  ASSERT_EQ(pcl::io::savePCDFileASCII(file.string(), cloud), 0);
  const std::string message = error_of([&] { read_organized_pcd(file); });
  EXPECT_NE(message.find(file.string()), std::string::npos) << message;
  EXPECT_NE(message.find("not organized"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
}

TEST(Pcd, MissingFileNoXyzAndAllNanAreErrorsNamingTheFile) {
  const fs::path missing = temp_file("missing.pcd");
  EXPECT_NE(error_of([&] { read_organized_pcd(missing); }).find(missing.string() + ": no such file"), std::string::npos);

  pcl::PointCloud<pcl::Normal> normals(8, 8);
  const fs::path no_xyz = temp_file("normals.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(no_xyz.string(), normals), 0);
  const std::string m1 = error_of([&] { read_organized_pcd(no_xyz); });
  EXPECT_NE(m1.find(no_xyz.string() + ": PCD has no x/y/z"), std::string::npos) << m1;

  pcl::PointCloud<pcl::PointXYZ> empty(8, 8, pcl::PointXYZ(NAN, NAN, NAN));
  empty.is_dense = false;
  const fs::path all_nan = temp_file("nan.pcd");
  ASSERT_EQ(pcl::io::savePCDFileBinary(all_nan.string(), empty), 0);
  const std::string m2 = error_of([&] { read_organized_pcd(all_nan); });
  EXPECT_NE(m2.find(all_nan.string() + ": PCD holds no valid point"), std::string::npos) << m2;

  const fs::path garbage = temp_file("garbage.pcd");
  { std::ofstream(garbage) << "not a point cloud\n"; }
  EXPECT_NE(error_of([&] { read_organized_pcd(garbage); }).find(garbage.string() + ": not a PCD file"), std::string::npos);
}
