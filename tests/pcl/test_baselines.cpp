// The PCL baselines separate a box from the table and return objects-only labels in image layout.
#include <gtest/gtest.h>

#include <map>

#include "clutterseg/pcl/baselines.hpp"
#include "scenes.hpp"

namespace {

using namespace clutterseg;

struct Separation {
  double box_share = 0;          // share of the box's pixels carrying its most common non-zero label
  double table_as_box = 0;       // share of the table's pixels carrying that label
  double table_zero = 0;         // share of the table's pixels labelled 0
};

// Compares baseline labels with the rendering's ground truth (1 = the box, 0 = table) on valid pixels.
Separation separation(const cv::Mat& labels, const synth::Rendering& truth) {
  std::map<int, int> on_box;
  int box = 0, table = 0, table_zero = 0;
  for (int i = 0; i < static_cast<int>(labels.total()); ++i) {
    if (truth.depth.at<float>(i) <= 0) continue;
    if (truth.labels.at<int>(i) == 1) {
      ++box;
      if (labels.at<int>(i) != 0) ++on_box[labels.at<int>(i)];
    } else {
      ++table;
      if (labels.at<int>(i) == 0) ++table_zero;
    }
  }
  int best = 0, best_count = 0;
  for (auto [label, count] : on_box)
    if (count > best_count) best = label, best_count = count;
  int table_as_box = 0;
  for (int i = 0; i < static_cast<int>(labels.total()); ++i)
    if (truth.depth.at<float>(i) > 0 && truth.labels.at<int>(i) == 0 && best != 0 && labels.at<int>(i) == best)
      ++table_as_box;
  return {box ? double(best_count) / box : 0, table ? double(table_as_box) / table : 0,
          table ? double(table_zero) / table : 0};
}

void expect_box_separated(const baselines::BaselineResult& r, const synth::Rendering& truth) {
  ASSERT_EQ(r.labels.type(), CV_32S);
  ASSERT_EQ(r.labels.size(), truth.depth.size());
  const Separation s = separation(r.labels, truth);
  EXPECT_GT(s.box_share, 0.8) << "the box is not mostly one object";
  EXPECT_LT(s.table_as_box, 0.02) << "the table is merged with the box";
  EXPECT_GT(s.table_zero, 0.9) << "the table is not dropped (objects-only labels)";
  ASSERT_FALSE(r.timings_ms.empty());
  EXPECT_EQ(r.timings_ms.back().first, "total");
}

// The baselines' settings come from PCL examples written for 640x480 Kinect clouds (at 320x240, LCCP's
// 7.5 mm voxels hold too few points and it merges this box with the table), so the scenes are rendered
// at 640x480.
scenes::TestScene at_640(scenes::TestScene scene) {
  scene.camera = synth::default_camera(640, 480);
  return scene;
}

}  // namespace

TEST(Baselines, LccpSeparatesBoxFromTable) {
  const auto scene = at_640(scenes::box_on_plane());
  const auto truth = scene.render();
  expect_box_separated(baselines::segment_lccp(truth.depth, scene.camera), truth);
}

TEST(Baselines, OrganizedSeparatesBoxFromTable) {
  const auto scene = at_640(scenes::box_on_plane());
  const auto truth = scene.render();
  expect_box_separated(baselines::segment_organized(truth.depth, scene.camera), truth);
}

TEST(Baselines, MillimetreDepthGivesTheSameObjectsAsMetres) {
  const auto scene = at_640(scenes::box_on_plane());
  const auto truth = scene.render();
  cv::Mat mm;
  truth.depth.convertTo(mm, CV_16U, 1000.0);
  expect_box_separated(baselines::segment_organized(mm, scene.camera), truth);
}

TEST(Baselines, PlaneOnlySceneHasNoObjects) {
  const auto scene = at_640(scenes::plane_scene());
  const auto truth = scene.render();
  EXPECT_EQ(cv::countNonZero(baselines::segment_organized(truth.depth, scene.camera).labels), 0);
  EXPECT_EQ(cv::countNonZero(baselines::segment_lccp(truth.depth, scene.camera).labels), 0);
}

TEST(Baselines, EmptyDepthAndWrongIntrinsicsAreErrors) {
  const auto scene = at_640(scenes::box_on_plane());
  EXPECT_THROW(baselines::segment_lccp(cv::Mat(), scene.camera), Error);
  EXPECT_THROW(baselines::segment_organized(cv::Mat(480, 640, CV_32F, cv::Scalar(0)), scene.camera), Error);
  Camera wrong = scene.camera;
  wrong.width = 320;
  EXPECT_THROW(baselines::segment_organized(scene.render().depth, wrong), Error);
}
