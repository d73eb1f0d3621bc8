// Paper f/g): co-planar flat patches whose gap is explained by occlusion are linked; co-planar
// patches with background between them are not (paper Fig. 5, green and red boxes).
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "clutterseg/coplanarity.hpp"
#include "clutterseg/parallel.hpp"
#include "scene_patches.hpp"

using namespace clutterseg;
using namespace clutterseg::scenes;

namespace {

struct SplitBox {
  Segmented s;
  std::vector<int> front, top;  // the two visible parts of each face of the occluded box
};

SplitBox split_box(const Params& params = {}) {
  const TestScene scene = occluded_box_split();
  SplitBox b{segment_scene(scene, params), {}, {}};
  const auto on_box = patches_on(b.s, 1);
  b.front = facing(b.s, on_box, camera_direction(scene, {0, -1, 0}));
  b.top = facing(b.s, on_box, direction_up(scene));
  return b;
}

const Patch& patch(const Segmented& s, int i) { return s.result.patches[static_cast<size_t>(i)]; }

// Two equal boxes with table between them, and the one top patch of each.
struct TwoTops {
  TestScene scene;
  Segmented s;
  std::vector<int> top1, top2;
};

TwoTops two_tops() {
  TwoTops t{separate_boxes(), {}, {}, {}};
  t.s = segment_scene(t.scene);
  t.top1 = facing(t.s, patches_on(t.s, 1), direction_up(t.scene));
  t.top2 = facing(t.s, patches_on(t.s, 2), direction_up(t.scene));
  return t;
}

}  // namespace

TEST(Coplanarity, OccludedFaceIsJoinedAcrossTheOccluder) {
  const SplitBox b = split_box();
  ASSERT_EQ(b.front.size(), 2u);
  ASSERT_EQ(b.top.size(), 2u);
  const Camera camera = occluded_box_split().camera;
  const Params::Coplanarity p;
  EXPECT_TRUE(coplanar(patch(b.s, b.front[0]), patch(b.s, b.front[1]), b.s.result.points, camera, p, 1));
  EXPECT_TRUE(coplanar(patch(b.s, b.top[0]), patch(b.s, b.top[1]), b.s.result.points, camera, p, 1));
  // Front and top of the same box are not one plane.
  EXPECT_FALSE(coplanar(patch(b.s, b.front[0]), patch(b.s, b.top[0]), b.s.result.points, camera, p, 1));

  // Among all patches (table, occluder, box parts), exactly the two split faces are joined.
  const auto pairs = coplanar_pairs(b.s.result.patches, {}, b.s.result.points, camera, p, 1);
  const std::vector<PatchPair> expected = {{std::min(b.top[0], b.top[1]), std::max(b.top[0], b.top[1])},
                                           {std::min(b.front[0], b.front[1]), std::max(b.front[0], b.front[1])}};
  std::vector<PatchPair> sorted_expected = expected;
  std::sort(sorted_expected.begin(), sorted_expected.end());
  EXPECT_EQ(pairs, sorted_expected);
}

TEST(Coplanarity, TopsOfSeparateBoxesWithTableBetweenAreNotJoined) {
  const auto [scene, s, top1, top2] = two_tops();
  ASSERT_EQ(top1.size(), 1u);
  ASSERT_EQ(top2.size(), 1u);
  // Same height, parallel: only the occlusion check tells them apart.
  EXPECT_NEAR(patch(s, top1[0]).centroid.dot(patch(s, top1[0]).mean_normal),
              patch(s, top2[0]).centroid.dot(patch(s, top1[0]).mean_normal), 0.003);
  EXPECT_FALSE(coplanar(patch(s, top1[0]), patch(s, top2[0]), s.result.points, scene.camera, {}, 1));
  Params::Coplanarity blind;  // accepting any share of samples behind, the tops would be joined
  blind.behind_fraction = 1.0;
  EXPECT_TRUE(coplanar(patch(s, top1[0]), patch(s, top2[0]), s.result.points, scene.camera, blind, 1));
  EXPECT_TRUE(coplanar_pairs(s.result.patches, {}, s.result.points, scene.camera, {}, 1).empty());
}

TEST(Coplanarity, SurvivesSensorNoise) {
  // Gaussian depth noise of 1 mm per metre squared (Kinect-like growth with z^2), fixed noise seed;
  // at 1.5 mm the pre-segmentation itself merges the box's top and front, so that is not tested here.
  const TestScene scene = occluded_box_split();
  Segmented s{scene.render(), {}};
  cv::Mat noise(s.truth.depth.size(), CV_32F);
  cv::RNG(3).fill(noise, cv::RNG::NORMAL, 0, 0.001);
  cv::Mat noisy = s.truth.depth + noise.mul(s.truth.depth.mul(s.truth.depth));
  noisy.setTo(0, s.truth.depth == 0);
  s.result = segment(noisy, scene.camera);
  const auto on_box = patches_on(s, 1);
  const auto front = facing(s, on_box, camera_direction(scene, {0, -1, 0}));
  const auto top = facing(s, on_box, direction_up(scene));
  ASSERT_EQ(front.size(), 2u);
  ASSERT_EQ(top.size(), 2u);
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    EXPECT_TRUE(coplanar(patch(s, front[0]), patch(s, front[1]), s.result.points, scene.camera, {}, seed)) << seed;
    EXPECT_TRUE(coplanar(patch(s, top[0]), patch(s, top[1]), s.result.points, scene.camera, {}, seed)) << seed;
  }
}

TEST(Coplanarity, SkipsLinkedPairsAndObeysTheSwitch) {
  const SplitBox b = split_box();
  const Camera camera = occluded_box_split().camera;
  const PatchPair front{std::min(b.front[0], b.front[1]), std::max(b.front[0], b.front[1])};
  const auto pairs = coplanar_pairs(b.s.result.patches, {{front.second, front.first}}, b.s.result.points, camera, {}, 1);
  EXPECT_EQ(pairs.size(), 1u);
  EXPECT_EQ(std::count(pairs.begin(), pairs.end(), front), 0);
  Params::Coplanarity off;
  off.enabled = false;
  EXPECT_TRUE(coplanar_pairs(b.s.result.patches, {}, b.s.result.points, camera, off, 1).empty());
}

TEST(Coplanarity, CurvedPatchesAreNeverCoplanar) {  // curved by histogram and by their points
  const TestScene scene = lying_cylinder_occluded();
  const Segmented s = segment_scene(scene);
  const auto parts = patches_on(s, 1);
  ASSERT_EQ(parts.size(), 2u);
  ASSERT_TRUE(patch(s, parts[0]).curved);
  EXPECT_FALSE(coplanar(patch(s, parts[0]), patch(s, parts[1]), s.result.points, scene.camera, {}, 1));
}

// Beyond the paper: a flat face whose normal histogram counts as curved (sensor noise on a thin or far
// face) takes part when its points are planar, and then needs an occluder in front of the gap.
namespace {
Patch with_noisy_histogram(Patch patch) {
  patch.curved = true;
  return patch;
}
}  // namespace

TEST(Coplanarity, APlanarFaceWithANoisyHistogramJoinsAcrossAnOccluder) {
  const SplitBox b = split_box();
  const Camera camera = occluded_box_split().camera;
  const Patch a = with_noisy_histogram(patch(b.s, b.front[0])), c = with_noisy_histogram(patch(b.s, b.front[1]));
  EXPECT_TRUE(coplanar(a, c, b.s.result.points, camera, {}, 1));  // the occluder stands in front of the gap
  Params::Coplanarity paper;  // flat patches only
  paper.planar_share = 0;
  EXPECT_FALSE(coplanar(a, c, b.s.result.points, camera, paper, 1));
  Params::Coplanarity far_in_front;  // more of every line in front than the occluder covers
  far_in_front.front_fraction = 0.99;
  EXPECT_FALSE(coplanar(a, c, b.s.result.points, camera, far_in_front, 1));
}

TEST(Coplanarity, TouchingCoplanarTopsWithNothingInFrontStayApart) {
  // Two boxes' tops at one height. With the background test blinded (as when the gap between two touching
  // boxes shows nothing behind), flat tops are joined; tops that count as curved need an occluder in front
  // of the gap, and there is none.
  const auto [scene, s, top1, top2] = two_tops();
  ASSERT_EQ(top1.size(), 1u);
  ASSERT_EQ(top2.size(), 1u);
  Params::Coplanarity blind;
  blind.behind_fraction = 1.0;
  const Patch a = with_noisy_histogram(patch(s, top1[0])), c = with_noisy_histogram(patch(s, top2[0]));
  EXPECT_TRUE(coplanar(patch(s, top1[0]), patch(s, top2[0]), s.result.points, scene.camera, blind, 1));
  EXPECT_FALSE(coplanar(a, c, s.result.points, scene.camera, blind, 1));
  blind.front_fraction = 0;
  EXPECT_TRUE(coplanar(a, c, s.result.points, scene.camera, blind, 1));
}

TEST(Coplanarity, AngleToleranceIsHonoured) {
  // The two parts' normals, estimated next to the occluder's edges, differ by about a degree.
  const SplitBox b = split_box();
  Params::Coplanarity strict;
  strict.angle_deg = 0.05;
  EXPECT_FALSE(coplanar(patch(b.s, b.front[0]), patch(b.s, b.front[1]), b.s.result.points, occluded_box_split().camera,
                        strict, 1));
}

TEST(Coplanarity, DeterministicForAnySeedAndThreadCount) {
  const SplitBox b = split_box();
  const Camera camera = occluded_box_split().camera;
  const auto& r = b.s.result;
  set_threads(1);
  const auto one = coplanar_pairs(r.patches, {}, r.points, camera, {}, 7);
  set_threads(2);
  EXPECT_EQ(coplanar_pairs(r.patches, {}, r.points, camera, {}, 7), one);
  set_threads(0);
  for (std::uint64_t seed : {1, 2, 3, 99}) EXPECT_EQ(coplanar_pairs(r.patches, {}, r.points, camera, {}, seed).size(), 2u);
}

TEST(Coplanarity, SameDecisionsAtVga) {
  // Every threshold is physical or scaled with the resolution: 640x480 decides as 320x240 does.
  for (auto make : {occluded_box_split, separate_boxes}) {
    TestScene scene = make();
    scene.camera = synth::default_camera(640, 480);
    const Segmented s = segment_scene(scene);
    const auto pairs = coplanar_pairs(s.result.patches, {}, s.result.points, scene.camera, {}, 1);
    if (make == occluded_box_split) {
      ASSERT_EQ(pairs.size(), 2u);
      const auto on_box = patches_on(s, 1);
      for (const auto& [a, b] : pairs) {  // each joins two parts of one face of the occluded box
        EXPECT_EQ(std::count(on_box.begin(), on_box.end(), a) + std::count(on_box.begin(), on_box.end(), b), 2);
        EXPECT_GT(patch(s, a).mean_normal.dot(patch(s, b).mean_normal), 0.99f);
      }
    } else {
      EXPECT_TRUE(pairs.empty());
    }
  }
}
