// Paper d): adjacency and edge-pixel assignment, against the paper's naive window scan.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <set>

#include "clutterseg/adjacency.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/segmenter.hpp"
#include "scene_patches.hpp"
#include "scenes.hpp"

using namespace clutterseg;

namespace {

// The paper's rule read literally: every patch pixel in the disc of radius r, nearest in 3D wins
// (ties to the smaller label). O(edge pixels x r^2): the reference, for small images only.
Assignment naive_assignment(const cv::Mat& labels, const cv::Mat& points, int radius, double d_max) {
  Assignment out;
  out.labels = labels.clone();
  std::set<PatchPair> pairs;
  const float d2_max = static_cast<float>(d_max * d_max);
  for (int y = 0; y < labels.rows; ++y)
    for (int x = 0; x < labels.cols; ++x) {
      const cv::Vec3f p = points.at<cv::Vec3f>(y, x);
      if (labels.at<int>(y, x) != 0 || p[2] <= 0) continue;
      std::set<int> seen;
      float best = d2_max;
      int best_label = 0;
      for (int dy = -radius; dy <= radius; ++dy)
        for (int dx = -radius; dx <= radius; ++dx) {
          const int xx = x + dx, yy = y + dy;
          if (dx * dx + dy * dy > radius * radius || xx < 0 || yy < 0 || xx >= labels.cols || yy >= labels.rows) continue;
          const int l = labels.at<int>(yy, xx);
          const cv::Vec3f q = points.at<cv::Vec3f>(yy, xx);
          if (l <= 0 || q[2] <= 0) continue;
          const cv::Vec3f d = p - q;
          const float d2 = d.dot(d);
          if (d2 >= d2_max) continue;
          seen.insert(l);
          if (d2 < best || (d2 == best && l < best_label)) { best = d2; best_label = l; }
        }
      out.labels.at<int>(y, x) = best_label;
      for (int a : seen)
        for (int b : seen)
          if (a < b) pairs.insert({a - 1, b - 1});
    }
  out.adjacent.assign(pairs.begin(), pairs.end());
  return out;
}

// Points of a small depth image seen with a VGA Kinect's angular resolution (about 2 mm per pixel at 1 m).
cv::Mat points_of(const cv::Mat& depth) {
  Camera camera;
  camera.fx = camera.fy = 525;
  camera.cx = depth.cols / 2.0;
  camera.cy = depth.rows / 2.0;
  camera.width = depth.cols;
  camera.height = depth.rows;
  return depth_to_points(depth, camera);
}

using Stage = scenes::Segmented;  // pre-segmentation (core patches) and ground truth

Stage presegment(const scenes::TestScene& scene) { return scenes::segment_scene(scene); }

int truth_of(const Stage& s, int patch_index) {
  return scenes::majority_label(s.result.patches[static_cast<size_t>(patch_index)].pixels, s.truth.labels);
}

}  // namespace

TEST(Adjacency, EdgeColumnBetweenTwoPatchesOfOnePlaneIsSplitBetweenThem) {
  // A plane at 1 m facing the camera; columns 10..13 are edge pixels between patch 1 and patch 2.
  cv::Mat depth(12, 24, CV_32F, cv::Scalar(1.0f));
  cv::Mat labels(12, 24, CV_32S, cv::Scalar(1));
  labels.colRange(10, 14).setTo(0);
  labels.colRange(14, 24).setTo(2);
  const Assignment a = assign_edge_pixels(labels, points_of(depth), 2, 3, 0.015);
  ASSERT_EQ(a.adjacent, (std::vector<PatchPair>{{0, 1}}));
  for (int y = 0; y < 12; ++y) {
    EXPECT_EQ(a.labels.at<int>(y, 10), 1);
    EXPECT_EQ(a.labels.at<int>(y, 11), 1);
    EXPECT_EQ(a.labels.at<int>(y, 12), 2);
    EXPECT_EQ(a.labels.at<int>(y, 13), 2);
  }
}

TEST(Adjacency, NeighboursInTheImageButNotIn3DAreNotAdjacent) {
  // Patch 2 is 10 cm behind patch 1: the edge pixels (at patch 1's depth) see only patch 1.
  cv::Mat depth(12, 24, CV_32F, cv::Scalar(1.0f));
  depth.colRange(14, 24).setTo(1.1f);
  cv::Mat labels(12, 24, CV_32S, cv::Scalar(1));
  labels.colRange(10, 14).setTo(0);
  labels.colRange(14, 24).setTo(2);
  const Assignment a = assign_edge_pixels(labels, points_of(depth), 2, 3, 0.015);
  EXPECT_TRUE(a.adjacent.empty());
  EXPECT_EQ(a.labels.at<int>(5, 12), 1);
}

TEST(Adjacency, PixelsBeyondRadiusOrDistanceStayUnassigned) {
  // A wide band of edge pixels: only those within r (3 px) of a patch are assigned; invalid pixels
  // are never assigned.
  cv::Mat depth(8, 30, CV_32F, cv::Scalar(1.0f));
  depth.at<float>(4, 4) = 0;
  cv::Mat labels(8, 30, CV_32S, cv::Scalar(0));
  labels.colRange(0, 3).setTo(1);
  const Assignment a = assign_edge_pixels(labels, points_of(depth), 1, 3, 0.015);
  EXPECT_EQ(a.labels.at<int>(2, 5), 1);   // 3 px away
  EXPECT_EQ(a.labels.at<int>(2, 6), 0);   // 4 px away
  EXPECT_EQ(a.labels.at<int>(4, 4), 0);   // no depth
  EXPECT_EQ(a.labels.at<int>(4, 5), 1);   // seen across the hole
}

TEST(Adjacency, BoxFacesAreAdjacentToEachOtherAndTheSidesToTheTable) {
  const Stage s = presegment(scenes::box_on_plane());
  const Assignment a = assign_edge_pixels(s.result.core_patch_labels, s.result.points,
                                          static_cast<int>(s.result.patches.size()), 7, 0.015);
  int box_box = 0, box_table = 0;
  for (const auto& [p, q] : a.adjacent) {
    const int tp = truth_of(s, p), tq = truth_of(s, q);
    box_box += tp == 1 && tq == 1;
    box_table += (tp == 0) != (tq == 0);
  }
  EXPECT_GE(box_box, 2);   // top-front, top-side, front-side: at least two of them
  EXPECT_GE(box_table, 1);
  // Edge pixels go to the object they lie on: count box edge pixels given to the table.
  int wrong = 0, assigned = 0;
  const int* core = s.result.core_patch_labels.ptr<int>();
  for (int i = 0; i < static_cast<int>(a.labels.total()); ++i) {
    const int l = a.labels.ptr<int>()[i];
    if (core[i] != 0 || l == 0) continue;
    ++assigned;
    wrong += (truth_of(s, l - 1) == 0) != (s.truth.labels.ptr<int>()[i] == 0);
  }
  EXPECT_GT(assigned, 500);
  EXPECT_LT(wrong, assigned / 20);
}

// The fast propagation against the naive scan on every test scene (see docs/ADJACENCY.md for what
// may differ): the same adjacency, and the same patch for nearly every edge pixel.
TEST(Adjacency, FastMatchesNaiveScanOnTestScenes) {
  for (const auto& scene : {scenes::box_on_plane(), scenes::stacked_boxes(), scenes::occluded_box(),
                            scenes::side_by_side_boxes(), scenes::staircase(), scenes::cup(),
                            scenes::lying_cylinder_occluded()}) {
    const Stage s = presegment(scene);
    const int n = static_cast<int>(s.result.patches.size());
    const Assignment fast = assign_edge_pixels(s.result.core_patch_labels, s.result.points, n, 7, 0.015);
    const Assignment naive = naive_assignment(s.result.core_patch_labels, s.result.points, 7, 0.015);
    EXPECT_EQ(fast.adjacent, naive.adjacent);
    int differ = 0, edge = 0;
    for (int i = 0; i < static_cast<int>(fast.labels.total()); ++i) {
      edge += s.result.core_patch_labels.ptr<int>()[i] == 0;
      differ += fast.labels.ptr<int>()[i] != naive.labels.ptr<int>()[i];
    }
    EXPECT_LE(differ, edge / 200) << differ << " of " << edge << " edge pixels differ";
  }
}

TEST(Adjacency, SameInputSameOutput) {
  const Stage s = presegment(scenes::occluded_box());
  const int n = static_cast<int>(s.result.patches.size());
  const Assignment a = assign_edge_pixels(s.result.core_patch_labels, s.result.points, n, 7, 0.015);
  const Assignment b = assign_edge_pixels(s.result.core_patch_labels, s.result.points, n, 7, 0.015);
  EXPECT_EQ(a.adjacent, b.adjacent);
  EXPECT_EQ(cv::countNonZero(a.labels != b.labels), 0);
}

// The same on a real 640x480 Kinect frame (r = 14 px): the numbers in docs/ADJACENCY.md.
TEST(Adjacency, FastMatchesNaiveScanOnARealKinectFrame) {
  const std::filesystem::path set = std::filesystem::path(CLUTTERSEG_DATA_DIR) / "osd-kinect";
  if (!std::filesystem::exists(set / "depth" / "test63.png")) GTEST_SKIP() << "no " << set;
  const Camera camera = read_camera_json(set / "camera.json");
  Params p;
  p.smoothing.temporal = false;
  const Result pre = segment(read_depth_png(set / "depth" / "test63.png"), camera, p);
  const int n = static_cast<int>(pre.patches.size());
  const auto t0 = std::chrono::steady_clock::now();
  const Assignment fast = assign_edge_pixels(pre.core_patch_labels, pre.points, n, 14, 0.015);
  const auto t1 = std::chrono::steady_clock::now();
  const Assignment naive = naive_assignment(pre.core_patch_labels, pre.points, 14, 0.015);
  const auto t2 = std::chrono::steady_clock::now();
  int differ = 0, edge = 0;
  for (int i = 0; i < static_cast<int>(fast.labels.total()); ++i) {
    if (pre.core_patch_labels.ptr<int>()[i] != 0 || pre.points.ptr<cv::Vec3f>()[i][2] <= 0) continue;
    ++edge;
    differ += fast.labels.ptr<int>()[i] != naive.labels.ptr<int>()[i];
  }
  std::printf("[ info ] fast %.1f ms, naive %.1f ms; %d of %d edge pixels differ; pairs %zu vs %zu\n",
              std::chrono::duration<double, std::milli>(t1 - t0).count(),
              std::chrono::duration<double, std::milli>(t2 - t1).count(), differ, edge, fast.adjacent.size(),
              naive.adjacent.size());
  EXPECT_LE(differ, edge / 100);
  // Every pair the fast scheme finds is a naive pair; it may miss a pair seen only across another patch.
  for (const auto& pair : fast.adjacent) EXPECT_TRUE(std::binary_search(naive.adjacent.begin(), naive.adjacent.end(), pair));
  EXPECT_GE(fast.adjacent.size() + 2, naive.adjacent.size());
}
