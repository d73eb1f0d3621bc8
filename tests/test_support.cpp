// Beyond the paper: the table, decided per patch (support.hpp), on scenes and patch lists built for it.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <set>

#include "clutterseg/patches.hpp"
#include "clutterseg/support.hpp"
#include "scene_patches.hpp"

using namespace clutterseg;
using namespace clutterseg::scenes;

namespace {

Patch patch_with(int id, std::vector<int> pixels, bool table, cv::Rect bbox) {
  Patch p;
  p.id = id;
  p.pixels = std::move(pixels);
  p.table = table;
  p.bbox = bbox;
  return p;
}

}  // namespace

TEST(Support, TheTableNotTheWallAndNotAPlaneFacingDown) {
  const Segmented s = segment_scene(box_before_wall());
  ASSERT_TRUE(s.result.support_plane);
  EXPECT_GT(s.result.support_plane->normal.dot(direction_up(box_before_wall())), 0.99f);
  // Every table patch lies in the plane, and no box patch does.
  for (const Patch& p : s.result.patches) {
    const int label = majority_label(p.pixels, s.truth.labels);
    if (label == 1) EXPECT_FALSE(p.table) << "patch " << p.id;
  }
}

TEST(Support, TheTableNotTheLargerFloorBelowIt) {
  // A small table 30 cm above a floor that fills most of the image: the floor is the largest plane (the
  // first candidate), but the boxes stand on the table. The table must win even though its region is
  // built only because its bound can beat the floor's score.
  Shape floor = table(1.5);
  floor.pose = Eigen::Translation3d(0, 0, -0.3);
  TestScene scene{{{floor, table(0.15), box(1, {-0.05, 0, 0.05}, {0.05, 0.04, 0.05}), box(2, {0.07, 0.02, 0.04}, {0.03, 0.03, 0.04})}}};
  const Segmented s = segment_scene(scene);
  ASSERT_TRUE(s.result.support_plane);
  const Eigen::Vector3f table_centre = (scene.world_to_camera * Eigen::Vector3d::Zero()).cast<float>();
  const Eigen::Vector3f floor_point = (scene.world_to_camera * Eigen::Vector3d(0, 0, -0.3)).cast<float>();
  EXPECT_LT(std::abs(s.result.support_plane->distance(table_centre)), 0.01f);
  EXPECT_GT(std::abs(s.result.support_plane->distance(floor_point)), 0.2f);
}

// Beyond the paper (support.glued_share): depth smoothed so much (filtered stereo: tabletop-realsense 000005
// and 000006) that no edge band is left around a box on the table or along the table's front edge. One patch
// holds the table, that box and the floor seen in front of the table (less than 60 % of it on one plane);
// the rest of the floor is a larger planar patch, and a second box on the table a patch of its own.
TEST(Support, ATableGluedToABoxAndTheFloorIsFoundAndCutFromThem) {
  Shape floor = table(1.5);
  floor.pose = Eigen::Translation3d(0, 0, -0.3);
  floor.label = 9;
  TestScene scene{{{floor, table(0.2), box(1, {-0.05, -0.02, 0.07}, {0.1, 0.06, 0.07}), box(2, {0.12, 0.08, 0.04}, {0.03, 0.03, 0.04})}}};
  const auto truth = scene.render();
  const cv::Mat points = depth_to_points(truth.depth, scene.camera);
  const int* label = truth.labels.ptr<int>();
  const int width = truth.depth.cols;
  int table_bottom = 0;  // the lowest image row of the table
  for (int i = 0; i < static_cast<int>(truth.depth.total()); ++i)
    if (label[i] == 0 && truth.depth.ptr<float>()[i] > 0) table_bottom = std::max(table_bottom, i / width);
  // The floor glued to the table: a strip of 8 rows below the table's front edge. The patch is then half
  // table, 30 % box and 20 % floor.
  const auto in_front = [&](int i) { return i / width > table_bottom && i / width <= table_bottom + 8; };
  std::vector<int> glued, rest_of_floor, small_box;
  for (int i = 0; i < static_cast<int>(truth.depth.total()); ++i) {
    if (!(truth.depth.ptr<float>()[i] > 0)) continue;
    if (label[i] == 0 || label[i] == 1 || (label[i] == 9 && in_front(i))) glued.push_back(i);
    else if (label[i] == 9) rest_of_floor.push_back(i);
    else small_box.push_back(i);
  }
  const Eigen::Vector3f up = direction_up(scene);
  std::vector<Patch> patches = {patch_with(1, glued, false, {}), patch_with(2, rest_of_floor, false, {}),
                                patch_with(3, small_box, false, {})};
  for (Patch& p : patches) p.mean_normal = up;  // what the table and the floor hold most of
  ASSERT_GT(rest_of_floor.size(), glued.size());
  const Eigen::Vector3f table_centre = (scene.world_to_camera * Eigen::Vector3d::Zero()).cast<float>();

  // Off: the glued patch is no plane, so the floor is the support.
  Params::Support off;
  off.glued_share = 0;
  const std::optional<Plane> floor_plane = find_support_plane(patches, points, scene.camera, off);
  ASSERT_TRUE(floor_plane);
  EXPECT_NEAR(floor_plane->distance(table_centre), 0.3f, 0.01f);

  // On (the default): the table, fitted on its own points, and the box and the floor cut from it.
  const Params::Support on;
  const std::optional<Plane> plane = find_support_plane(patches, points, scene.camera, on);
  ASSERT_TRUE(plane);
  EXPECT_LT(std::abs(plane->distance(table_centre)), 0.003f);
  EXPECT_GT(plane->normal.dot(up), 0.999f);
  cv::Mat patch_labels(truth.depth.size(), CV_32S, cv::Scalar(0)), edges(truth.depth.size(), CV_8U, cv::Scalar(255));
  for (const Patch& p : patches)
    for (int i : p.pixels) patch_labels.ptr<int>()[i] = p.id, edges.ptr<uchar>()[i] = 0;
  ASSERT_GT(cut_off_table(edges, patches, patch_labels, points, *plane, on, 50), 0);
  cv::Mat parts;  // of the glued patch
  cv::connectedComponents((edges == 0) & (patch_labels == 1), parts, 4);
  std::set<int> table_parts;
  for (int i : glued)
    if (label[i] == 0) table_parts.insert(parts.ptr<int>()[i]);
  table_parts.erase(0);  // the cut pixels
  // Every pixel of the box or the floor clear of the table's plane is cut off the table (the box's foot,
  // within the plane's tolerance, stays with it).
  int box_clear = 0, floor_clear = 0;
  for (int i : glued) {
    const cv::Vec3f q = points.ptr<cv::Vec3f>()[i];
    if (label[i] == 0 || std::abs(plane->distance({q[0], q[1], q[2]})) <= plane_tolerance(on.plane_band, q[2])) continue;
    (label[i] == 1 ? box_clear : floor_clear)++;
    EXPECT_FALSE(table_parts.count(parts.ptr<int>()[i])) << "pixel " << i << " of " << label[i] << " is still one patch with the table";
  }
  EXPECT_GT(box_clear, 2000);
  EXPECT_GT(floor_clear, 2000);
}

TEST(Support, APatchOfTwoParallelTopsIsSplitAtItsPlane) {
  // A box and a smaller one beside it, their tops 2 cm apart in height; one patch holding both tops, as
  // if the edges had a gap between them.
  TestScene scene{{{table(), box(1, {-0.06, 0, 0.05}, {0.06, 0.05, 0.05}), box(2, {0.03, 0, 0.07}, {0.03, 0.04, 0.07})}}};
  const auto truth = scene.render();
  const cv::Mat points = depth_to_points(truth.depth, scene.camera);
  const Eigen::Vector3f up = direction_up(scene);
  cv::Mat labels(truth.depth.size(), CV_32S, cv::Scalar(0)), edges(truth.depth.size(), CV_8U, cv::Scalar(255));
  std::vector<int> tops;
  for (int i = 0; i < static_cast<int>(truth.depth.total()); ++i) {
    const cv::Vec3f n = truth.normals.ptr<cv::Vec3f>()[i];
    if (truth.labels.ptr<int>()[i] > 0 && Eigen::Vector3f(n[0], n[1], n[2]).dot(up) > 0.99f) {
      tops.push_back(i);
      labels.ptr<int>()[i] = 1;
      edges.ptr<uchar>()[i] = 0;
    }
  }
  Patch both = patch_with(1, tops, false, cv::Rect(0, 0, 1, 1));
  ASSERT_GT(split_at_planes(edges, {both}, labels, points, 0.008, 50, std::nullopt, Params::Support{}), 50);
  // The cut leaves two 4-connected parts, one per box.
  cv::Mat parts;
  const int count = cv::connectedComponents(edges == 0, parts, 4) - 1;
  std::set<int> box_of_part[3];
  for (int i : tops) box_of_part[truth.labels.ptr<int>()[i]].insert(parts.ptr<int>()[i]);
  EXPECT_GE(count, 2);
  for (int part : box_of_part[1]) EXPECT_FALSE(part > 0 && box_of_part[2].count(part)) << "part " << part << " holds both tops";
  // A curved patch is never split, whatever its points.
  both.curved = true;
  cv::Mat untouched(truth.depth.size(), CV_8U, cv::Scalar(0));
  EXPECT_EQ(split_at_planes(untouched, {both}, labels, points, 0.008, 50, std::nullopt, Params::Support{}), 0);
}

TEST(Support, TablePiecesAreOneObjectButAFloorInsideAnObjectJoinsIt) {
  // Patches: 0 the table (largest), 1 a piece of table between objects 1 and 2, 2 a bowl's wall, 3 the
  // floor inside it, 4 a box.
  std::vector<Patch> patches = {patch_with(1, std::vector<int>(100), true, {0, 0, 100, 100}),
                                patch_with(2, std::vector<int>(10), true, {40, 40, 5, 5}),
                                patch_with(3, std::vector<int>(30), false, {10, 10, 20, 20}),
                                patch_with(4, std::vector<int>(10), true, {15, 15, 5, 5}),
                                patch_with(5, std::vector<int>(30), false, {50, 40, 10, 10})};
  const std::vector<std::pair<int, int>> adjacent = {{0, 2}, {0, 4}, {1, 2}, {1, 4}, {2, 3}};
  std::vector<int> object_of_patch = {0, 1, 2, 3, 4};  // every patch its own object, as after the cut
  std::vector<float> cut_cost = {10, 11, 12, 13, 14};
  EXPECT_EQ(settle_table(patches, adjacent, object_of_patch, cut_cost), 1);
  EXPECT_FALSE(patches[3].table);
  EXPECT_TRUE(patches[1].table);
  // Table pieces 0 and 1 are one object, the floor is the bowl's; objects renumbered in order.
  EXPECT_EQ(object_of_patch, (std::vector<int>{0, 0, 1, 1, 2}));
  EXPECT_EQ(cut_cost, (std::vector<float>{10, 12, 14}));
}

TEST(Support, EdgePixelsGivenToTheTableAboveItAreReleased) {
  const Segmented s = segment_scene(box_on_plane());
  ASSERT_TRUE(s.result.support_plane);
  const Plane& plane = *s.result.support_plane;
  // Every pixel the table kept after step d) lies within the pixel band of its plane.
  for (int i = 0; i < static_cast<int>(s.result.patch_labels.total()); ++i) {
    const int l = s.result.patch_labels.ptr<int>()[i];
    if (l <= 0 || !s.result.patches[static_cast<size_t>(l - 1)].table) continue;
    const cv::Vec3f q = s.result.points.ptr<cv::Vec3f>()[i];
    ASSERT_LE(plane.distance({q[0], q[1], q[2]}), plane_tolerance(Params{}.support.pixel_band, q[2]) + 1e-6f) << "pixel " << i;
  }
}

// Beyond the paper: a patch lying in the table's band whose normals spread far more than the table's (a
// bowl's floor) is not table; the small flat table pieces between objects stay table.
TEST(Support, ACurvedPatchInTheBandIsNoTable) {
  std::vector<Patch> patches(4);
  const int bins[4] = {10, 6, 21, 40}, size[4] = {5000, 300, 800, 900};
  for (int k = 0; k < 4; ++k) {
    patches[static_cast<size_t>(k)].occupied_bins = bins[k];
    patches[static_cast<size_t>(k)].pixels.resize(static_cast<size_t>(size[k]));
    patches[static_cast<size_t>(k)].table = k != 3;  // patch 3: an object, left alone
  }
  Params::Support params;
  params.curved_bins_ratio = 0;
  EXPECT_EQ(unmark_curved_table(patches, params), 0);
  params = Params::Support{};  // default 2: more than 20 bins, twice the largest table patch's 10
  EXPECT_EQ(unmark_curved_table(patches, params), 1);
  EXPECT_TRUE(patches[0].table);
  EXPECT_TRUE(patches[1].table);
  EXPECT_FALSE(patches[2].table);
  EXPECT_FALSE(patches[3].table);
}

namespace {

// A 60x60 frame: table (patch 1, object 1) everywhere but a disc of radius 10 at (30, 30), a second table
// patch (2: a pan's floor in the table's band), inside a rim of object 2 (radius 10 to 14) that stage j)
// made; `rim_share` of the rim, from the left, is that object's, the rest table.
struct Floor {
  cv::Mat object_labels, patch_labels;
  std::vector<Patch> patches;
  std::vector<int> object_of_patch{0, 0};
};

Floor pan_floor(double rim_share, cv::Point centre = {30, 30}) {
  Floor f{cv::Mat(60, 60, CV_32S, cv::Scalar(1)), cv::Mat(60, 60, CV_32S, cv::Scalar(1)), {}};
  std::vector<int> table, floor;
  for (int y = 0; y < 60; ++y)
    for (int x = 0; x < 60; ++x) {
      const double r = std::hypot(x - centre.x, y - centre.y);
      const bool rim = r >= 10 && r < 14 && x - (centre.x - 14) < rim_share * 28;
      if (r < 10) {
        f.patch_labels.at<int>(y, x) = 2;
        floor.push_back(y * 60 + x);
      } else {
        if (rim) f.object_labels.at<int>(y, x) = 2, f.patch_labels.at<int>(y, x) = 0;
        else table.push_back(y * 60 + x);
      }
    }
  f.patches = {patch_with(1, table, true, {0, 0, 60, 60}),
               patch_with(2, floor, true, {centre.x - 9, centre.y - 9, 19, 19})};
  return f;
}

}  // namespace

TEST(Support, AFloorInsideARimThatStageJMadeJoinsTheRim) {
  Floor f = pan_floor(1.0);
  EXPECT_EQ(claim_enclosed_floors(f.object_labels, f.patch_labels, f.patches, f.object_of_patch, 2, 2, 0.8), 1);
  EXPECT_FALSE(f.patches[1].table);
  EXPECT_EQ(f.object_of_patch[1], 1);
  EXPECT_EQ(f.object_labels.at<int>(30, 30), 2);  // the floor is the rim's object
  EXPECT_EQ(f.object_labels.at<int>(2, 2), 1);    // the table is still the table
  EXPECT_TRUE(f.patches[0].table);
}

TEST(Support, AFloorNotEnclosedByOneObjectStaysTable) {
  const auto claimed = [](Floor f, double share) {
    const cv::Mat before = f.object_labels.clone();
    const int n = claim_enclosed_floors(f.object_labels, f.patch_labels, f.patches, f.object_of_patch, 2, 2, share);
    EXPECT_EQ(n == 0, cv::countNonZero(before != f.object_labels) == 0);
    return n;
  };
  EXPECT_EQ(claimed(pan_floor(0.6), 0.8), 0);               // table on 40 % of its rim: a piece of table
  EXPECT_EQ(claimed(pan_floor(1.0, {12, 30}), 0.8), 0);     // the ring reaches the image border
  EXPECT_EQ(claimed(pan_floor(1.0), 0), 0);                 // switched off
  EXPECT_EQ(claimed(pan_floor(0.9), 0.8), 1);               // 80 % of the rim and more: enclosed
}
