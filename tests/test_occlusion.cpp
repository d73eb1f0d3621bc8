// The occlusion check (paper f/g, h): is the gap between two surface points hidden by something in
// front of the straight 3D segment, or open to the background behind it?
#include <gtest/gtest.h>

#include "clutterseg/normals.hpp"
#include "clutterseg/occlusion.hpp"
#include "scene_patches.hpp"

using namespace clutterseg;

namespace {

const Camera kCamera = synth::default_camera(64, 48);

cv::Mat wall_points(float z) { return depth_to_points(cv::Mat(48, 64, CV_32F, cv::Scalar(z)), kCamera); }

// The camera-frame point that pixel (u, v) sees at depth z.
Eigen::Vector3f at_pixel(double u, double v, double z) {
  return {static_cast<float>((u - kCamera.cx) / kCamera.fx * z), static_cast<float>((v - kCamera.cy) / kCamera.fy * z),
          static_cast<float>(z)};
}

}  // namespace

TEST(Occlusion, SegmentOnTheSurfaceIsNotBehindIt) {
  EXPECT_EQ(behind_fraction(at_pixel(5, 10, 1), at_pixel(60, 40, 1), wall_points(1), kCamera, 0.01), 0.0);
}

TEST(Occlusion, BackgroundBehindTheSegmentCounts) {
  // A wall 10 cm behind the segment: every sample looks through the gap into the background.
  EXPECT_EQ(behind_fraction(at_pixel(5, 10, 0.9), at_pixel(60, 40, 0.9), wall_points(1), kCamera, 0.01), 1.0);
  // A wall in front of the segment occludes it: nothing counts.
  EXPECT_EQ(behind_fraction(at_pixel(5, 10, 1.1), at_pixel(60, 40, 1.1), wall_points(1), kCamera, 0.01), 0.0);
  // Within the tolerance: noise, not background.
  EXPECT_EQ(behind_fraction(at_pixel(5, 10, 0.995), at_pixel(60, 40, 0.995), wall_points(1), kCamera, 0.01), 0.0);
}

TEST(Occlusion, HalfOpenGapGivesHalf) {
  // Left half of the image is an occluder at 0.5 m, right half background at 2 m; the segment at 1 m
  // runs along a row across both halves.
  cv::Mat depth(48, 64, CV_32F, cv::Scalar(2.f));
  depth(cv::Rect(0, 0, 32, 48)).setTo(0.5f);
  const double f = behind_fraction(at_pixel(0, 24, 1), at_pixel(63, 24, 1), depth_to_points(depth, kCamera), kCamera, 0.01);
  EXPECT_NEAR(f, 0.5, 0.03);
}

TEST(Occlusion, InvalidPixelsNeverCountAgainst) {
  cv::Mat depth(48, 64, CV_32F, cv::Scalar(2.f));
  depth(cv::Rect(10, 0, 44, 48)).setTo(0.f);  // no measurement in the middle
  // Valid samples at both ends lie on the segment's depth: the hole between them does not count.
  cv::Mat points = depth_to_points(depth, kCamera);
  EXPECT_EQ(behind_fraction(at_pixel(2, 24, 2), at_pixel(61, 24, 2), points, kCamera, 0.01), 0.0);
  // No valid sample at all: nothing speaks against the segment.
  EXPECT_EQ(behind_fraction(at_pixel(12, 24, 1), at_pixel(50, 24, 1), points, kCamera, 0.01), 0.0);
}

TEST(Occlusion, FollowsPerspectiveOnASteepPlane) {
  // Plane z = 1 + 0.5 x, seen from 0.77 m to 1.43 m across the image: depth along an image line is not
  // linear in the image (10 cm off in the middle), the inverse depth is.
  cv::Mat depth(48, 64, CV_32F);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) depth.at<float>(v, u) = static_cast<float>(1.0 / (1.0 - 0.5 * (u - kCamera.cx) / kCamera.fx));
  const cv::Mat points = depth_to_points(depth, kCamera);
  auto point = [&](int v, int u) { const cv::Vec3f p = points.at<cv::Vec3f>(v, u); return Eigen::Vector3f(p[0], p[1], p[2]); };
  EXPECT_EQ(behind_fraction(point(24, 1), point(24, 62), points, kCamera, 0.001), 0.0);
  // Diagonally, pixel centres lie up to half a pixel beside the line: about 1 cm/px of depth slope here.
  EXPECT_EQ(behind_fraction(point(24, 62), point(40, 1), points, kCamera, 0.005), 0.0);
}

TEST(Occlusion, SegmentLeavingTheImageIsBounded) {
  // One end projects far outside the image: only the pixels inside are sampled, and it returns.
  const double f = behind_fraction(at_pixel(30, 24, 1), at_pixel(5000, 24, 1), wall_points(1.5), kCamera, 0.01);
  EXPECT_EQ(f, 1.0);
}

TEST(Occlusion, OccludedFaceVersusTableBetweenBoxes) {
  // Paper Fig. 5: the two parts of a face split by an occluder in front (green) against two boxes'
  // tops with bare table between them (red).
  using namespace scenes;
  const auto occluded = segment_scene(occluded_box_split());
  const auto front = facing(occluded, patches_on(occluded, 1), camera_direction(occluded_box_split(), {0, -1, 0}));
  ASSERT_EQ(front.size(), 2u);
  const auto& r = occluded.result;
  const Camera& camera = occluded_box_split().camera;
  EXPECT_LE(behind_fraction(r.patches[static_cast<size_t>(front[0])].centroid, r.patches[static_cast<size_t>(front[1])].centroid,
                            r.points, camera, 0.01), 0.05);

  const auto apart = segment_scene(separate_boxes());
  const auto top = direction_up(separate_boxes());
  const auto tops = std::vector<int>{facing(apart, patches_on(apart, 1), top).at(0), facing(apart, patches_on(apart, 2), top).at(0)};
  EXPECT_GT(behind_fraction(apart.result.patches[static_cast<size_t>(tops[0])].centroid,
                            apart.result.patches[static_cast<size_t>(tops[1])].centroid, apart.result.points, camera, 0.01), 0.3);
}
