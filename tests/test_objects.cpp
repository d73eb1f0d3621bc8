// Per-object outputs: statistics, the support plane and the objects-only view.
#include <gtest/gtest.h>

#include "clutterseg/normals.hpp"
#include "clutterseg/objects.hpp"
#include "clutterseg/patches.hpp"
#include "clutterseg/support.hpp"
#include "clutterseg/segmenter.hpp"
#include "scene_patches.hpp"
#include "scenes.hpp"

using namespace clutterseg;

namespace {

Result run(const scenes::TestScene& scene, const synth::Rendering& truth) {
  Params p;
  p.smoothing.temporal = false;
  return segment(truth.depth, scene.camera, p);
}


}  // namespace

TEST(Objects, StatisticsOfARectangleAndThePose) {
  // Object 1: a 20 x 10 px patch of a plane at 1 m (about 38 x 19 mm); object 2: one pixel.
  Camera cam;
  cam.fx = cam.fy = 525;
  cam.cx = 20;
  cam.cy = 15;
  cam.width = 40;
  cam.height = 30;
  const cv::Mat points = depth_to_points(cv::Mat(30, 40, CV_32F, cv::Scalar(1.0f)), cam);
  cv::Mat labels(30, 40, CV_32S, cv::Scalar(0));
  labels(cv::Rect(10, 10, 20, 10)).setTo(1);
  labels.at<int>(0, 0) = 2;
  cam.camera_to_robot(0, 3) = 1.0;  // robot frame: camera frame shifted 1 m along x
  const auto objects = describe_objects(labels, points, {0, 0, 1}, {0.25f}, cam);
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(objects[0].id, 1);
  EXPECT_EQ(objects[0].pixel_count, 200);
  EXPECT_NEAR(objects[0].centroid.x(), 1.0 + (19.5 - 20) / 525.0, 1e-4);
  EXPECT_NEAR(objects[0].centroid.z(), 1.0, 1e-5);
  EXPECT_NEAR(objects[0].box.extents(0), 19 / 525.0, 1e-4);  // largest extent first
  EXPECT_NEAR(objects[0].box.extents(1), 9 / 525.0, 1e-4);
  EXPECT_NEAR(objects[0].box.extents(2), 0.0, 1e-5);
  EXPECT_NEAR(std::abs(objects[0].box.axes.col(0).x()), 1.0, 1e-4);
  EXPECT_NEAR(objects[0].box.axes.determinant(), 1.0, 1e-4);
  EXPECT_NEAR(objects[0].box.center.x(), objects[0].centroid.x(), 1e-4);
  EXPECT_EQ(objects[0].patches, (std::vector<int>{0, 1}));
  EXPECT_FLOAT_EQ(objects[0].cut_cost, 0.25f);
  EXPECT_EQ(objects[1].patches, (std::vector<int>{2}));
  EXPECT_TRUE(std::isinf(objects[1].cut_cost));  // no cut given: one patch
}

TEST(Objects, TableIsTheSupportAndObjectsOnlyDropsIt) {
  const auto scene = scenes::box_on_plane();
  const auto truth = scene.render();
  const Result r = run(scene, truth);
  ASSERT_TRUE(r.support_plane.has_value());
  // The table normal (world z) in the camera frame.
  const Eigen::Vector3f up = (scene.world_to_camera.linear() * Eigen::Vector3d::UnitZ()).cast<float>();
  EXPECT_GT(r.support_plane->normal.dot(up), 0.999f);
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  EXPECT_LT(scenes::kept_share(view, truth.labels, 0, truth.depth), 0.01);
  EXPECT_GT(scenes::kept_share(view, truth.labels, 1, truth.depth), 0.95);
  EXPECT_EQ(std::count_if(r.objects.begin(), r.objects.end(), [](const Object& o) { return o.support; }), 1);
}

TEST(Objects, EmptyTableIsStillTheSupport) {
  const auto scene = scenes::plane_scene();
  const auto truth = scene.render();
  const Result r = run(scene, truth);
  ASSERT_TRUE(r.support_plane.has_value());
  EXPECT_EQ(cv::countNonZero(objects_only(r.object_labels, r.objects)), 0);
}

TEST(Objects, WallIsBackgroundAndTheBoxIsKept) {
  const auto scene = scenes::box_before_wall();
  const auto truth = scene.render();
  const Result r = run(scene, truth);
  ASSERT_TRUE(r.support_plane.has_value());
  const Eigen::Vector3f up = (scene.world_to_camera.linear() * Eigen::Vector3d::UnitZ()).cast<float>();
  EXPECT_GT(r.support_plane->normal.dot(up), 0.99f);  // the table, not the wall
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  EXPECT_LT(scenes::kept_share(view, truth.labels, 0, truth.depth), 0.02);  // table and wall dropped
  EXPECT_GT(scenes::kept_share(view, truth.labels, 1, truth.depth), 0.95);
}

// Beyond the paper (support.wall_hides_share): pcl-organized's laptop lid was dropped as a wall.
TEST(Objects, AnUprightBoardOnTheTableIsAnObjectNotAWall) {
  const auto scene = scenes::board_on_table();
  const auto truth = scene.render();
  const Result r = run(scene, truth);
  ASSERT_TRUE(r.support_plane.has_value());
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  EXPECT_LT(scenes::kept_share(view, truth.labels, 0, truth.depth), 0.02);
  EXPECT_GT(scenes::kept_share(view, truth.labels, 1, truth.depth), 0.9);
  // Without the rule the board is a wall: the switch is what keeps it.
  Params p;
  p.smoothing.temporal = false;
  p.support.wall_hides_share = 0;
  const Result off = segment(truth.depth, scene.camera, p);
  EXPECT_LT(scenes::kept_share(objects_only(off.object_labels, off.objects), truth.labels, 1, truth.depth), 0.1);
}

TEST(Objects, StackedBoxesStaySeparateAndSameInputGivesSameLabels) {
  const auto scene = scenes::stacked_boxes();
  const auto truth = scene.render();
  const Result a = run(scene, truth), b = run(scene, truth);
  EXPECT_EQ(cv::countNonZero(a.object_labels != b.object_labels), 0);
  // The majority object of each box's pixels differs.
  auto majority = [&](int label) {
    std::map<int, int> count;
    for (int i = 0; i < static_cast<int>(truth.labels.total()); ++i)
      if (truth.labels.ptr<int>()[i] == label) ++count[a.object_labels.ptr<int>()[i]];
    return std::max_element(count.begin(), count.end(), [](auto& x, auto& y) { return x.second < y.second; })->first;
  };
  EXPECT_NE(majority(1), majority(2));
  EXPECT_NE(majority(1), majority(0));
}

TEST(Objects, ObjectTheEdgesLeftInTheTableIsCutOff) {
  // As if the edges had not separated box and table: one patch of every pixel with depth.
  const auto scene = scenes::box_on_plane();
  const auto truth = scene.render();
  const Result r = run(scene, truth);
  ASSERT_TRUE(r.support_plane.has_value());
  cv::Mat edges(truth.depth.size(), CV_8U, cv::Scalar(0));
  edges.setTo(255, truth.depth <= 0);
  const Params p;
  const Patches one = extract_patches(edges, r.depth, scene.camera, r.normals, p.patches, 50);
  ASSERT_EQ(one.patches.size(), 1u);
  const auto plane = find_support_plane(one.patches, r.points, scene.camera, p.support);
  ASSERT_TRUE(plane.has_value());
  EXPECT_GT(plane->normal.dot(r.support_plane->normal), 0.999f);  // the table's plane, not a compromise
  ASSERT_GT(cut_off_table(edges, one.patches, one.labels, r.points, *plane, p.support, 50), 0);
  const Patches two = extract_patches(edges, r.depth, scene.camera, r.normals, p.patches, 50);
  ASSERT_GE(two.patches.size(), 2u);
  // The box is now patches of its own, off the table; the table patch lies in the plane.
  int box_pixels = 0, table_patches = 0;
  for (const Patch& patch : two.patches) {
    const bool table = lies_in(patch, r.points, *plane, p.support);
    table_patches += table;
    for (int i : patch.pixels) box_pixels += !table && truth.labels.ptr<int>()[i] == 1;
  }
  EXPECT_EQ(table_patches, 1);
  EXPECT_GT(box_pixels, 0.8 * cv::countNonZero(truth.labels == 1));
}

TEST(Objects, SameLabelsForAnyThreadCount) {
  const auto scene = scenes::occluded_box();
  const auto truth = scene.render();
  Params p;
  p.smoothing.temporal = false;
  p.threads = 1;
  const Result one = segment(truth.depth, scene.camera, p);
  p.threads = 2;
  const Result two = segment(truth.depth, scene.camera, p);
  EXPECT_EQ(cv::countNonZero(one.object_labels != two.object_labels), 0);
  EXPECT_EQ(cv::countNonZero(one.patch_labels != two.patch_labels), 0);
  ASSERT_EQ(one.objects.size(), two.objects.size());
  for (size_t i = 0; i < one.objects.size(); ++i) EXPECT_EQ(one.objects[i].centroid, two.objects[i].centroid);
}
