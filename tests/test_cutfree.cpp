// Paper e): cut-free neighbours on built point sets and on the analytic scenes.
#include <gtest/gtest.h>

#include <map>

#include "clutterseg/adjacency.hpp"
#include "clutterseg/cutfree.hpp"
#include "clutterseg/segmenter.hpp"
#include "scene_patches.hpp"
#include "scenes.hpp"

using namespace clutterseg;

namespace {

// Two patches in one point image: `a` fills row 0, `b` row 1 (points given directly).
struct TwoPatches {
  cv::Mat points;
  Patch a, b;
};

TwoPatches build(const std::function<Eigen::Vector3f(int)>& a_point, const std::function<Eigen::Vector3f(int)>& b_point,
                 int n = 100) {
  TwoPatches t;
  t.points = cv::Mat(2, n, CV_32FC3);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3f p = a_point(i), q = b_point(i);
    t.points.at<cv::Vec3f>(0, i) = {p.x(), p.y(), p.z()};
    t.points.at<cv::Vec3f>(1, i) = {q.x(), q.y(), q.z()};
    t.a.pixels.push_back(i);
    t.b.pixels.push_back(n + i);
  }
  return t;
}

// A 10 x 10 grid of points, 1 cm apart, spanned by two directions around `origin` (metres).
auto grid(Eigen::Vector3f origin, Eigen::Vector3f e1, Eigen::Vector3f e2) {
  return [=](int i) { return Eigen::Vector3f(origin + 0.01f * static_cast<float>(i % 10) * e1 + 0.01f * static_cast<float>(i / 10) * e2); };
}

struct Stage : scenes::Segmented {
  std::vector<PatchPair> adjacent;
};

// The paper's patches: with the seam split (patches.seam_theta, seams.hpp) the exact stacked-boxes scene
// has other patches, and cut-free keeps a link between the two boxes among them (docs/RESULTS.md, section
// 11); this file tests cut-free on the pre-segmentation it was written for.
Stage presegment(const scenes::TestScene& scene) {
  Params params;
  params.patches.seam_theta = 0;
  Stage s{scenes::segment_scene(scene, params), {}};
  s.adjacent = assign_edge_pixels(s.result.core_patch_labels, s.result.points, static_cast<int>(s.result.patches.size()), 7, 0.015).adjacent;
  return s;
}

int truth_of(const Stage& s, int patch_index) {
  return scenes::majority_label(s.result.patches[static_cast<size_t>(patch_index)].pixels, s.truth.labels);
}

}  // namespace

TEST(CutFree, AWallThroughATableCutsItButTheTableDoesNotCutTheWall) {
  // Table: z = 1 plane, x and y in [0, 9] cm. Wall: x = 4.5 cm, standing on the table (toward the camera).
  const auto t = build(grid({0, 0, 1}, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY()),
                       grid({0.045f, 0, 0.99f}, -Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitY()));
  Params::CutFree p;
  EXPECT_FALSE(one_side_of(t.b, t.a, t.points, p, 1));  // the wall's plane splits the table in halves
  EXPECT_TRUE(one_side_of(t.a, t.b, t.points, p, 1));   // the wall lies on one side of the table plane
}

TEST(CutFree, TwoFacesOfABoxDoNotCutEachOther) {
  // Top (z = 1, x in [0, 9] cm) and front face (x = 0 going toward the camera): a convex edge.
  const auto t = build(grid({0.0f, 0, 1}, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY()),
                       grid({-0.005f, 0, 0.99f}, -Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitY()));
  Params::CutFree p;
  EXPECT_TRUE(one_side_of(t.a, t.b, t.points, p, 1));
  EXPECT_TRUE(one_side_of(t.b, t.a, t.points, p, 1));
}

TEST(CutFree, ToleranceAllowsAFewWrongSidePoints) {
  // 5 of 100 table points lie 2 cm below the wall's foot line on the far side: under the 10 % tolerance.
  auto table = [](int i) { return Eigen::Vector3f(i < 5 ? 0.08f : 0.01f * static_cast<float>(i % 4), 0.01f * static_cast<float>(i / 10), 1.0f); };
  const auto t = build(table, grid({0.045f, 0, 0.99f}, -Eigen::Vector3f::UnitZ(), Eigen::Vector3f::UnitY()));
  Params::CutFree p;
  EXPECT_TRUE(one_side_of(t.b, t.a, t.points, p, 1));
  p.wrong_side_fraction = 0.01;
  EXPECT_FALSE(one_side_of(t.b, t.a, t.points, p, 1));
}

TEST(CutFree, BoxOnTableKeepsFaceLinksAndDropsTableLinks) {
  const Stage s = presegment(scenes::box_on_plane());
  Params::CutFree p;
  const auto kept = cut_free_pairs(s.adjacent, s.result.patches, s.result.points, p, 1);
  int box_box = 0;
  for (const auto& [a, b] : s.adjacent) box_box += truth_of(s, a) == 1 && truth_of(s, b) == 1;
  int kept_box_box = 0;
  for (const auto& [a, b] : kept) {
    EXPECT_FALSE((truth_of(s, a) == 0) != (truth_of(s, b) == 0)) << "box-table link kept: " << a << "-" << b;
    kept_box_box += truth_of(s, a) == 1 && truth_of(s, b) == 1;
  }
  EXPECT_GE(box_box, 2);
  EXPECT_EQ(kept_box_box, box_box);
}

TEST(CutFree, StackedBoxesAreNotLinked) {
  const Stage s = presegment(scenes::stacked_boxes());
  const auto kept = cut_free_pairs(s.adjacent, s.result.patches, s.result.points, Params::CutFree{}, 1);
  bool lower_upper_adjacent = false;
  for (const auto& [a, b] : s.adjacent) lower_upper_adjacent |= truth_of(s, a) + truth_of(s, b) == 3 && truth_of(s, a) != 0 && truth_of(s, b) != 0;
  EXPECT_TRUE(lower_upper_adjacent);  // the test means something: the upper box touches the lower one
  for (const auto& [a, b] : kept) EXPECT_EQ(truth_of(s, a), truth_of(s, b)) << a << "-" << b;
}

TEST(CutFree, TwoBoxesSideBySideAreNotLinked) {
  const Stage s = presegment(scenes::two_boxes_apart());
  const auto kept = cut_free_pairs(s.adjacent, s.result.patches, s.result.points, Params::CutFree{}, 1);
  for (const auto& [a, b] : kept) EXPECT_EQ(truth_of(s, a), truth_of(s, b)) << a << "-" << b;
}

TEST(CutFree, SkippingSimilarNormalsIsTheAuthorsChoiceAndCanBeSwitchedOff) {
  // A table and a low step 5 mm above it, touching: parallel, so skipped (linked) by default.
  const auto t = build(grid({0, 0, 1}, Eigen::Vector3f::UnitX(), Eigen::Vector3f::UnitY()),
                       [](int i) { return Eigen::Vector3f(0.095f + 0.01f * static_cast<float>(i % 10), 0.01f * static_cast<float>(i / 10), i % 2 ? 0.97f : 1.03f); });
  std::vector<Patch> patches = {t.a, t.b};
  patches[0].mean_normal = patches[1].mean_normal = Eigen::Vector3f(0, 0, -1);
  Params::CutFree p;
  EXPECT_EQ(cut_free_pairs({{0, 1}}, patches, t.points, p, 1).size(), 1u);
  p.skip_similar = false;  // the table plane has b's points on both sides
  EXPECT_TRUE(cut_free_pairs({{0, 1}}, patches, t.points, p, 1).empty());
}

TEST(CutFree, SameSeedSameResult) {
  const Stage s = presegment(scenes::occluded_box());
  Params::CutFree p;
  p.skip_similar = false;
  const auto a = cut_free_pairs(s.adjacent, s.result.patches, s.result.points, p, 7);
  const auto b = cut_free_pairs(s.adjacent, s.result.patches, s.result.points, p, 7);
  EXPECT_EQ(a, b);
}

namespace {

// Two stacked boxes seen from the front, built point by point in a camera looking down 45 degrees: the
// upper box's front (rows 0-9) stands 8 mm behind the lower box's front (rows 13-29) and 1-4 cm above
// the lower box's top (rows 10-12, patch 1). The fronts are one patch (2), joined at the left end
// (columns 0-2 of rows 10-12), as a gap in the edge band joins them in stacked-boxes-000000.
struct ForkedFronts {
  cv::Mat points, labels;
  std::vector<Patch> patches;
  Eigen::Vector3f up;
};

ForkedFronts forked_fronts(bool cutter_is_a_side = false) {
  const Eigen::Vector3f up = Eigen::Vector3f(0, -1, -1).normalized(), toward = Eigen::Vector3f(0, 1, -1).normalized(),
                        right = Eigen::Vector3f::UnitX(), origin(0, 0, 1);
  const auto at = [&](float x, float height, float back) { return Eigen::Vector3f(origin + x * right + height * up - back * toward); };
  constexpr int kSize = 30;
  ForkedFronts f{cv::Mat(kSize, kSize, CV_32FC3), cv::Mat(kSize, kSize, CV_32S, cv::Scalar(0)), {}, up};
  f.patches.resize(2);
  for (int y = 0; y < kSize; ++y)
    for (int x = 0; x < kSize; ++x) {
      const float u = 0.004f * static_cast<float>(x);
      Eigen::Vector3f q;
      int label = 2;
      if (y < 10) q = at(u, 0.04f - 0.003f * static_cast<float>(y), 0.008f);          // upper front
      else if (y < 13 && x < 3) q = at(u, 0.f, 0.004f);                                // the joint
      else if (y < 13) q = at(u, 0.f, 0.003f * static_cast<float>(y - 10)), label = 1;  // lower top
      else q = at(u, -0.003f * static_cast<float>(y - 12), 0.f);                        // lower front
      f.points.at<cv::Vec3f>(y, x) = {q.x(), q.y(), q.z()};
      f.labels.at<int>(y, x) = label;
      f.patches[static_cast<size_t>(label - 1)].pixels.push_back(y * kSize + x);
    }
  for (int k = 0; k < 2; ++k) f.patches[static_cast<size_t>(k)].id = k + 1;
  f.patches[0].mean_normal = cutter_is_a_side ? Eigen::Vector3f(-right) : up;
  f.patches[1].mean_normal = toward;
  return f;
}

// The parts of patch `id` left 4-connected after `edges` are taken out.
int parts_of(const cv::Mat& labels, const cv::Mat& edges, int id) {
  cv::Mat inside = (labels == id) & (edges == 0), components;
  return cv::connectedComponents(inside, components, 4) - 1;
}

}  // namespace

TEST(CutFree, ATopCutsTheStackedFrontsPatchInTwo) {
  ForkedFronts f = forked_fronts();
  cv::Mat edges(f.labels.size(), CV_8U, cv::Scalar(0));
  ASSERT_EQ(parts_of(f.labels, edges, 2), 1);
  const Params::CutFree params;
  const int marked = split_cut_patches(edges, {{0, 1}}, {}, f.patches, f.labels, f.points, params, 20, f.up);
  EXPECT_GT(marked, 0);
  EXPECT_EQ(parts_of(f.labels, edges, 2), 2);  // the upper front apart from the lower one
  EXPECT_EQ(parts_of(f.labels, edges, 1), 1);  // the top is not touched
}

TEST(CutFree, NoSplitWhenLinkedNotATopOrSwitchedOff) {
  const auto marked = [](const ForkedFronts& f, const std::vector<PatchPair>& linked, const Params::CutFree& params) {
    cv::Mat edges(f.labels.size(), CV_8U, cv::Scalar(0));
    const int n = split_cut_patches(edges, {{0, 1}}, linked, f.patches, f.labels, f.points, params, 20, f.up);
    EXPECT_EQ(n == 0, cv::countNonZero(edges) == 0);
    return n;
  };
  const Params::CutFree params;
  EXPECT_EQ(marked(forked_fronts(), {{0, 1}}, params), 0);  // the pair passed the cut-free test
  EXPECT_EQ(marked(forked_fronts(true), {}, params), 0);     // a side's plane cuts a front that goes on past it
  Params::CutFree off;
  off.split_share = 0;
  EXPECT_EQ(marked(forked_fronts(), {}, off), 0);
}
