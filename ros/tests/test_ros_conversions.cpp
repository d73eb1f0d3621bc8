// The ROS layer's conversions alone (no master): parameters, input checks, intrinsics, output messages.
#include <gtest/gtest.h>

#include <clutterseg/objects.hpp>

#include <cmath>
#include <cstring>

#include "conversions.hpp"

namespace clutterseg_ros {
namespace {

XmlRpc::XmlRpcValue dictionary() {
  XmlRpc::XmlRpcValue v;
  v.begin();  // makes it a (empty) struct
  return v;
}

std::string error_of(const XmlRpc::XmlRpcValue& v) {
  try {
    params_from_ros(v, "/seg");
  } catch (const clutterseg::Error& e) {
    return e.what();
  }
  return "";
}

TEST(RosParams, NoParametersGiveTheDefaults) {
  const clutterseg::Params p = params_from_ros(XmlRpc::XmlRpcValue(), "/seg");
  EXPECT_EQ(p.graph.theta_c, clutterseg::Params{}.graph.theta_c);
  EXPECT_EQ(p.seed, clutterseg::Params{}.seed);
}

TEST(RosParams, NestedNamesReachTheParams) {
  XmlRpc::XmlRpcValue v = dictionary();
  v["graph"]["theta_c"] = 0.7;
  v["support"]["objects_only"] = true;
  v["smoothing"]["temporal_frames"] = 3;
  v["curvature"]["theta_h"] = 1;  // an integer where a double is expected: fine
  v["seed"] = 42;
  v["target_frame"] = std::string("base_link");  // the node's own: not passed to the core
  v["image_transport"] = std::string("raw");
  const clutterseg::Params p = params_from_ros(v, "/seg");
  EXPECT_DOUBLE_EQ(p.graph.theta_c, 0.7);
  EXPECT_TRUE(p.support.objects_only);
  EXPECT_EQ(p.smoothing.temporal_frames, 3);
  EXPECT_DOUBLE_EQ(p.curvature.theta_h, 1.0);
  EXPECT_EQ(p.seed, 42u);
}

TEST(RosParams, UnknownNamesAreRefusedWithTheRosName) {
  XmlRpc::XmlRpcValue v = dictionary();
  v["graph"]["theta_x"] = 0.7;
  const std::string e = error_of(v);
  EXPECT_NE(e.find("'graph.theta_x'"), std::string::npos) << e;
  EXPECT_NE(e.find("/seg/graph/theta_x"), std::string::npos) << e;

  XmlRpc::XmlRpcValue top = dictionary();
  top["theta_c"] = 0.7;  // belongs under graph/
  EXPECT_NE(error_of(top).find("/seg/theta_c"), std::string::npos) << error_of(top);
}

TEST(RosParams, WrongTypesAreRefused) {
  XmlRpc::XmlRpcValue v = dictionary();
  v["graph"]["theta_c"] = std::string("high");
  EXPECT_NE(error_of(v).find("ROS parameters in /seg"), std::string::npos) << error_of(v);

  XmlRpc::XmlRpcValue group = dictionary();
  group["graph"] = 0.5;  // a value where a dictionary is expected
  EXPECT_FALSE(error_of(group).empty());
}

sensor_msgs::Image depth_image(const std::string& encoding, uint32_t width, uint32_t height, uint32_t bytes) {
  sensor_msgs::Image image;
  image.encoding = encoding;
  image.width = width;
  image.height = height;
  image.step = width * bytes;
  image.data.resize(size_t{image.step} * height);
  return image;
}

sensor_msgs::CameraInfo info_of(uint32_t width, uint32_t height) {
  sensor_msgs::CameraInfo info;
  info.width = width;
  info.height = height;
  info.K = {525, 0, 319.5, 0, 526, 239.5, 0, 0, 1};
  return info;
}

TEST(RosInput, AcceptsMillimetresAndMetres) {
  EXPECT_FALSE(check_depth_frame(depth_image("16UC1", 640, 480, 2), info_of(640, 480)));
  EXPECT_FALSE(check_depth_frame(depth_image("mono16", 640, 480, 2), info_of(640, 480)));
  EXPECT_FALSE(check_depth_frame(depth_image("32FC1", 640, 480, 4), info_of(640, 480)));
  EXPECT_DOUBLE_EQ(*depth_unit_m("16UC1"), 0.001);
  EXPECT_DOUBLE_EQ(*depth_unit_m("32FC1"), 1.0);
}

TEST(RosInput, RefusesOtherEncodingsSizesAndIntrinsics) {
  const auto encoding = check_depth_frame(depth_image("rgb8", 640, 480, 3), info_of(640, 480));
  ASSERT_TRUE(encoding);
  EXPECT_NE(encoding->find("'rgb8'"), std::string::npos) << *encoding;

  const auto size = check_depth_frame(depth_image("16UC1", 640, 480, 2), info_of(320, 240));
  ASSERT_TRUE(size);
  EXPECT_NE(size->find("640x480"), std::string::npos) << *size;
  EXPECT_NE(size->find("320x240"), std::string::npos) << *size;

  sensor_msgs::CameraInfo uncalibrated = info_of(640, 480);
  uncalibrated.K = {};
  EXPECT_TRUE(check_depth_frame(depth_image("16UC1", 640, 480, 2), uncalibrated));

  sensor_msgs::Image truncated = depth_image("16UC1", 640, 480, 2);
  truncated.data.resize(100);
  EXPECT_TRUE(check_depth_frame(truncated, info_of(640, 480)));
}

TEST(RosInput, IntrinsicsComeFromK) {
  const clutterseg::Camera c = camera_from_info(info_of(640, 480), 0.001);
  EXPECT_EQ(c.fx, 525);
  EXPECT_EQ(c.fy, 526);
  EXPECT_EQ(c.cx, 319.5);
  EXPECT_EQ(c.cy, 239.5);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.depth_unit_m, 0.001);
}

// Objects 1 (a box on the table), 2 (the table) and 3 (a wall) in a 4x1 label image.
clutterseg::Result three_objects() {
  clutterseg::Result r;
  r.object_labels = (cv::Mat_<int>(1, 4) << 1, 2, 3, 0);
  clutterseg::Object box, table, wall;
  box.id = 1;
  box.pixel_count = 1;
  box.centroid = {0.1f, 0.0f, 1.0f};
  box.box.center = box.centroid;
  box.box.extents = {0.2f, 0.1f, 0.05f};
  box.cut_cost = 0.75f;
  table.id = 2;
  table.pixel_count = 1;
  table.support = true;
  table.centroid = {0.0f, 0.2f, 1.2f};
  wall.id = 3;
  wall.pixel_count = 1;
  wall.background = true;
  r.objects = {box, table, wall};
  clutterseg::Plane plane;
  plane.normal = {0, -1, 0};  // table at y = 0.2 in camera coordinates, normal towards the camera
  plane.offset = 0.2f;
  r.support_plane = plane;
  return r;
}

TEST(RosObjects, FullViewListsEveryObject) {
  const clutterseg::Result r = three_objects();
  std_msgs::Header header;
  header.frame_id = "camera";
  const ObjectArray m = objects_message(r, view_ids(r.object_labels, r.object_labels), Eigen::Isometry3d::Identity(), header);
  ASSERT_EQ(m.objects.size(), 3u);
  EXPECT_EQ(m.header.frame_id, "camera");
  EXPECT_EQ(m.objects[0].id, 1u);
  EXPECT_FLOAT_EQ(m.objects[0].confidence, 0.75f);
  EXPECT_DOUBLE_EQ(m.objects[0].box_size.x, 0.2f);
  EXPECT_TRUE(m.objects[1].support);
  EXPECT_TRUE(m.objects[2].background);
  ASSERT_TRUE(m.has_support_plane);
  EXPECT_NEAR(m.support_plane[1], -1.0, 1e-9);
  EXPECT_NEAR(m.support_plane[3], 0.2, 1e-7);
}

TEST(RosObjects, ObjectsOnlyViewListsTheViewsIds) {
  const clutterseg::Result r = three_objects();
  const cv::Mat view = clutterseg::objects_only(r.object_labels, r.objects);
  const std::vector<int> ids = view_ids(r.object_labels, view);
  EXPECT_EQ(ids, (std::vector<int>{0, 1, 0, 0}));
  const ObjectArray m = objects_message(r, ids, Eigen::Isometry3d::Identity(), std_msgs::Header());
  ASSERT_EQ(m.objects.size(), 1u);
  EXPECT_FALSE(m.objects[0].support);
  // The table is not listed, so the markers show it on its own.
  const auto markers = markers_message(m, r, Eigen::Isometry3d::Identity());
  ASSERT_GE(markers.markers.size(), 4u);
  EXPECT_EQ(markers.markers.front().action, visualization_msgs::Marker::DELETEALL);
  EXPECT_EQ(markers.markers.back().ns, "support");
}

TEST(RosObjects, TargetFrameMovesObjectsAndPlane) {
  const clutterseg::Result r = three_objects();
  Eigen::Isometry3d to = Eigen::Isometry3d::Identity();
  to.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  to.translation() = Eigen::Vector3d(1, 2, 3);
  const ObjectArray m = objects_message(r, view_ids(r.object_labels, r.object_labels), to, std_msgs::Header());
  const Eigen::Vector3d c = to * Eigen::Vector3d(0.1, 0.0, 1.0);
  EXPECT_NEAR(m.objects[0].centroid.x, c.x(), 1e-6);
  EXPECT_NEAR(m.objects[0].centroid.y, c.y(), 1e-6);
  EXPECT_NEAR(m.objects[0].centroid.z, c.z(), 1e-6);
  // A point on the table (camera y = 0.2) lies on the transformed plane.
  const Eigen::Vector3d on_table = to * Eigen::Vector3d(0.3, 0.2, 1.5);
  const auto& p = m.support_plane;
  EXPECT_NEAR(p[0] * on_table.x() + p[1] * on_table.y() + p[2] * on_table.z() + p[3], 0.0, 1e-6);
  // The plane's pose: origin on the plane under the table's centroid, z along the normal.
  const geometry_msgs::Pose pose = plane_pose(r, Eigen::Isometry3d::Identity());
  EXPECT_NEAR(pose.position.y, 0.2, 1e-6);
  EXPECT_NEAR(pose.position.z, 1.2, 1e-6);
  const Eigen::Quaterniond q(pose.orientation.w, pose.orientation.x, pose.orientation.y, pose.orientation.z);
  EXPECT_NEAR((q * Eigen::Vector3d::UnitZ() - Eigen::Vector3d(0, -1, 0)).norm(), 0.0, 1e-6);
}

TEST(RosCloud, OrganizedWithNanForMissingPointsAndLabels) {
  cv::Mat points(1, 2, CV_32FC3);
  points.at<cv::Vec3f>(0, 0) = {0.1f, 0.2f, 1.0f};
  points.at<cv::Vec3f>(0, 1) = {0, 0, 0};  // no measurement
  const cv::Mat labels = (cv::Mat_<int>(1, 2) << 7, 0);
  const sensor_msgs::PointCloud2 cloud = cloud_message(points, labels, std_msgs::Header());
  ASSERT_EQ(cloud.width, 2u);
  ASSERT_EQ(cloud.height, 1u);
  ASSERT_EQ(cloud.fields.size(), 4u);
  EXPECT_EQ(cloud.fields[3].name, "label");
  float xyz[3];
  uint32_t label;
  std::memcpy(xyz, cloud.data.data(), 12);
  std::memcpy(&label, cloud.data.data() + 12, 4);
  EXPECT_FLOAT_EQ(xyz[2], 1.0f);
  EXPECT_EQ(label, 7u);
  std::memcpy(xyz, cloud.data.data() + 16, 12);
  EXPECT_TRUE(std::isnan(xyz[0]) && std::isnan(xyz[2]));
}

}  // namespace
}  // namespace clutterseg_ros
