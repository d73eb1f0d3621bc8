// Beyond the paper: the contact cue (contact.hpp) on scenes built for it. Faces of one box meet in
// convex edges; a box meets the table, and a box the box it rests on, in concave creases.
#include <gtest/gtest.h>

#include "clutterseg/contact.hpp"
#include "clutterseg/segmenter.hpp"
#include "scene_patches.hpp"

using namespace clutterseg;
using namespace clutterseg::scenes;

namespace {

Params without_table() {
  Params p;
  p.smoothing.temporal = false;
  p.support.enabled = false;  // keep the table's links in the graph, to see how they are judged
  p.cutfree.enabled = false;  // the paper's cut-free test removes most box-table links on clean scenes
  return p;
}

// The graph link between two patches (nullptr if none).
const GraphEdge* link(const Result& r, int a, int b) {
  for (const auto& e : r.graph)
    if ((e.a == a && e.b == b) || (e.a == b && e.b == a)) return &e;
  return nullptr;
}

}  // namespace

TEST(Contact, BoxFacesMeetConvexlyAndTheTableConcavely) {
  const Segmented s = segment_scene(box_on_plane(), without_table());
  const std::vector<int> box = patches_on(s, 1), table = patches_on(s, 0);
  ASSERT_GE(box.size(), 2u);
  ASSERT_FALSE(table.empty());
  int convex = 0, concave = 0;
  for (int a : box) {
    for (int b : box)
      if (const GraphEdge* e = a < b ? link(s.result, a, b) : nullptr) {
        EXPECT_EQ(e->cue, Cue::Adjacent);
        EXPECT_GT(e->convexity, 0.5f);
        ++convex;
      }
    for (int t : table)
      if (const GraphEdge* e = link(s.result, a, t)) {
        EXPECT_EQ(e->cue, Cue::AdjacentConcave);
        EXPECT_LT(e->convexity, -0.5f);
        ++concave;
      }
  }
  EXPECT_GE(convex, 1);
  EXPECT_GE(concave, 1);
}

TEST(Contact, ConcaveLinksWeighLessAndTheSwitchTurnsThemOff) {
  Params p = without_table();
  const Segmented on = segment_scene(stacked_boxes(), p);
  p.convexity.enabled = false;
  const Segmented off = segment_scene(stacked_boxes(), p);
  int concave = 0;
  for (const auto& e : on.result.graph) concave += e.cue == Cue::AdjacentConcave;
  EXPECT_GT(concave, 0);
  for (const auto& e : off.result.graph) EXPECT_NE(e.cue, Cue::AdjacentConcave);
  // The same links, each no heavier with the cue than without it.
  ASSERT_EQ(on.result.graph.size(), off.result.graph.size());
  for (size_t k = 0; k < on.result.graph.size(); ++k) EXPECT_LE(on.result.graph[k].weight, off.result.graph[k].weight);
}

TEST(Contact, ClassifiesBuiltContacts) {
  // Two planes meeting at x = 0, one point pair per contact; normals facing the camera (-z).
  cv::Mat points(1, 8, CV_32FC3), nx(1, 8, CV_32F), ny(1, 8, CV_32F), nz(1, 8, CV_32F);
  const auto set = [&](int i, Eigen::Vector3f p, Eigen::Vector3f n) {
    points.at<cv::Vec3f>(0, i) = {p.x(), p.y(), p.z()};
    n.normalize();
    nx.at<float>(0, i) = n.x(); ny.at<float>(0, i) = n.y(); nz.at<float>(0, i) = n.z();
  };
  // Pixels 0, 1: a roof ridge (convex): left face tilted left, right face tilted right, ridge nearest.
  set(0, {-0.01f, 0, 1.0f}, {-1, 0, -1});
  set(1, {0.01f, 0, 1.0f}, {1, 0, -1});
  // Pixels 2, 3: a valley (concave): the same faces, the crease farthest.
  set(2, {-0.01f, 0, 1.0f}, {1, 0, -1});
  set(3, {0.01f, 0, 1.0f}, {-1, 0, -1});
  // Pixels 4, 5: a step: parallel faces 2 cm apart in depth, 1 cm apart sideways.
  set(4, {-0.005f, 0, 1.0f}, {0, 0, -1});
  set(5, {0.005f, 0, 1.02f}, {0, 0, -1});
  // Pixels 6, 7: one plane continued.
  set(6, {-0.01f, 0, 1.0f}, {0, 0, -1});
  set(7, {0.01f, 0, 1.0f}, {0, 0, -1});
  std::vector<Contact> contacts;
  for (int pair = 0; pair < 4; ++pair)
    for (int k = 0; k < 5; ++k) contacts.push_back({2 * pair, 2 * pair + 1, 2 * pair, 2 * pair + 1});
  const auto j = classify_junctions(contacts, points, NormalPlanes{nx, ny, nz}, Params::Convexity{});
  ASSERT_EQ(j.size(), 4u);
  EXPECT_EQ(j[0].kind, Junction::Convex);
  EXPECT_EQ(j[1].kind, Junction::Concave);
  EXPECT_EQ(j[2].kind, Junction::Step);
  EXPECT_EQ(j[3].kind, Junction::Flat);
  EXPECT_EQ(j[0].samples, 5);
  // One contact alone needs a crease three times as sharp: the roof still is one, a faint one is not.
  set(1, {0.01f, 0, 1.0f}, {0.1f, 0, -1});
  set(0, {-0.01f, 0, 1.0f}, {-0.1f, 0, -1});
  const auto single = classify_junctions({{0, 1, 0, 1}}, points, NormalPlanes{nx, ny, nz}, Params::Convexity{});
  EXPECT_EQ(single[0].kind, Junction::Flat);
  std::vector<Contact> five(5, {0, 1, 0, 1});
  EXPECT_EQ(classify_junctions(five, points, NormalPlanes{nx, ny, nz}, Params::Convexity{})[0].kind, Junction::Convex);
}


// Beyond the paper (convexity.top_angle_deg): a can standing flush with the front of a box (tabletop-realsense
// 000002, a can on a tin) touches the box's front with no crease, since the can's side runs on into it; only
// the can's crease with the box's top tells a contact. Hand-made patches in the camera frame (up = -y): A above
// the top B's plane, meeting B in a concave crease; C below it, meeting B in a convex edge; A touches C flat.
TEST(Contact, AnObjectOnATopTouchesTheFacesBelowItsEdgeAsAContact) {
  const int rows = 30, cols = 30;
  const auto make = [&](float c_from, float c_to, const Eigen::Vector3f& top_normal) {
    struct Scene {
      cv::Mat points;
      std::vector<Patch> patches;
    } scene{cv::Mat(rows, cols, CV_32FC3, cv::Scalar::all(0)), std::vector<Patch>(3)};
    const float y_from[3] = {0.02f, 0.1f, c_from}, y_to[3] = {0.09f, 0.1f, c_to};  // A, B (the top at y = 0.1), C
    for (int k = 0; k < 3; ++k) {
      Patch& patch = scene.patches[static_cast<size_t>(k)];
      patch.id = k + 1;
      for (int v = 10 * k; v < 10 * k + 10; ++v)
        for (int u = 0; u < cols; ++u) {
          const float t = static_cast<float>(v - 10 * k) / 9.f, x = 0.01f * static_cast<float>(u - cols / 2);
          const cv::Vec3f q(x, y_from[k] + t * (y_to[k] - y_from[k]), k == 1 ? 1.f + 0.01f * static_cast<float>(v - 10) : 1.f);
          scene.points.at<cv::Vec3f>(v, u) = q;
          patch.pixels.push_back(v * cols + u);
          patch.centroid += Eigen::Vector3f(q[0], q[1], q[2]);
        }
      patch.centroid /= static_cast<float>(patch.pixels.size());
      patch.mean_normal = k == 1 ? top_normal : Eigen::Vector3f(0, 0, -1);
    }
    return scene;
  };
  const auto junction = [](int a, int b, Junction kind) {
    PairJunction j;
    j.pair = {a, b};
    j.kind = kind;
    j.samples = 10;
    return j;
  };
  const std::vector<PairJunction> junctions = {junction(0, 1, Junction::Concave), junction(0, 2, Junction::Flat),
                                               junction(1, 2, Junction::Convex)};
  const Eigen::Vector3f up(0, -1, 0);
  const Params::Convexity params;
  const auto flush = make(0.11f, 0.2f, up);
  EXPECT_EQ(contacts_across_tops(junctions, flush.patches, flush.points, up, params), std::vector<PatchPair>{PatchPair(0, 2)});
  EXPECT_EQ(contacts_across_tops(junctions, flush.patches, flush.points, -up, params).size(), 1u);  // either sign of up
  Params::Convexity off;
  off.top_angle_deg = 0;
  EXPECT_TRUE(contacts_across_tops(junctions, flush.patches, flush.points, up, off).empty());
  const auto wall = make(0.11f, 0.2f, Eigen::Vector3f(1, 0, 0));  // B faces sideways: no top
  EXPECT_TRUE(contacts_across_tops(junctions, wall.patches, wall.points, up, params).empty());
  const auto above = make(0.02f, 0.09f, up);  // C above B's plane as well: no face below the top's edge
  EXPECT_TRUE(contacts_across_tops(junctions, above.patches, above.points, up, params).empty());
  const std::vector<PairJunction> creased = {junction(0, 1, Junction::Concave), junction(0, 2, Junction::Concave),
                                             junction(1, 2, Junction::Convex)};  // already weighed down
  EXPECT_TRUE(contacts_across_tops(creased, flush.patches, flush.points, up, params).empty());
  const std::vector<PairJunction> convex_top = {junction(0, 1, Junction::Convex), junction(0, 2, Junction::Flat),
                                                junction(1, 2, Junction::Convex)};  // A is B's own face
  EXPECT_TRUE(contacts_across_tops(convex_top, flush.patches, flush.points, up, params).empty());
}
