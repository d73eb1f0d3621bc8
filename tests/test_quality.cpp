// Segmentation quality, held to what docs/RESULTS.md reports (issue 14): the hand-labelled osd-kinect
// frames of data/handlabelled/, the YCB-Video frames and the synthetic Table II families. A change that
// merges objects again, keeps table in an object or drops object faces fails here.
#include <gtest/gtest.h>

#include <filesystem>
#include <set>

#include "clutterseg/error_breakdown.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/objects.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/synth/dataset.hpp"

using namespace clutterseg;
namespace fs = std::filesystem;

namespace {

struct Totals {
  double overlap_f = 0, tp = 0, fp = 0, background = 0, dropped = 0;
  int frames = 0, merged_objects = 0;
};

// One frame's scores added to `t`, in the objects-only view, as `clutterseg eval` scores it.
void add(Totals& t, const cv::Mat& truth, const Result& r) {
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  const FrameScores s = score_frame(truth, view);
  const ErrorBreakdown b = error_breakdown(truth, view, s.matches);
  t.overlap_f += s.overlap_f;
  t.tp += s.tp;
  t.fp += s.fp;
  t.background += b.background;
  t.dropped += b.dropped;
  t.merged_objects += b.merged_objects;
  ++t.frames;
}

// Sums to means over the frames.
void average(Totals& t) {
  for (double* v : {&t.overlap_f, &t.tp, &t.fp, &t.background, &t.dropped}) *v /= std::max(1, t.frames);
}

// The frames of a folder, each on its own (no temporal history) unless `stream`.
Totals score(const fs::path& depth_dir, const fs::path& label_dir, const Camera& camera, bool stream) {
  Totals t;
  Params p;
  p.smoothing.temporal = stream;
  Segmenter segmenter(p);
  std::vector<fs::path> frames;
  for (const auto& e : fs::directory_iterator(label_dir)) frames.push_back(e.path().filename());
  std::sort(frames.begin(), frames.end());
  for (const auto& name : frames)
    add(t, read_label_png(label_dir / name), segmenter.segment(read_depth_png(depth_dir / name), camera));
  average(t);
  return t;
}

}  // namespace

TEST(Quality, HandLabelledOsdFrames) {
  const fs::path dev = CLUTTERSEG_DATA_DIR;
  const Totals t = score(dev / "osd-kinect" / "depth", fs::path(CLUTTERSEG_SOURCE_DIR) / "data/handlabelled/osd-kinect/label",
                         read_camera_json(dev / "osd-kinect" / "camera.json"), false);
  ASSERT_EQ(t.frames, 5);
  // docs/RESULTS.md, "The hand-labelled regression set": F 89.4, tp 89.7, fp 15.1, 6 objects in merges (of 46),
  // table in objects 0.7 % (mean over the frames here: F 0.894); before the seam split of section 11: F 86.2,
  // fp 22.0, 9 merged; before issue 14: F 81, fp 25, 14 merged, 1.9 %. (Its labels leave pixels without
  // depth at 0, so the hole fill of remaining.hole_px costs it 0.3 F and 0.6 fp, and the shadow fill of
  // remaining.shadow_baseline 0.2 F and 0.4 fp: RESULTS.md sections 7 and 8.)
  EXPECT_GE(t.overlap_f, 0.89);
  EXPECT_GE(t.tp, 0.89);
  EXPECT_LE(t.fp, 0.16);
  EXPECT_LE(t.merged_objects, 6);
  EXPECT_LE(t.background, 0.01);
}

TEST(Quality, YcbVideoFrontFacesAreKept) {
  const fs::path dev = CLUTTERSEG_DATA_DIR;
  const Totals t = score(dev / "ycbv-0000" / "depth", dev / "ycbv-0000" / "label",
                         read_camera_json(dev / "ycbv-0000" / "camera.json"), true);
  ASSERT_EQ(t.frames, 10);
  // docs/RESULTS.md: tp 96.1 and 1.0 % of the objects' pixels dropped (94.0 and 2.3 % before the seam split
  // of section 11; before issue 14: tp 83.9, and a band of 15 mm above the table dropped from every object;
  // without the hole fill, remaining.hole_px: tp 90.5 and 5.1 % dropped).
  EXPECT_GE(t.tp, 0.95);
  EXPECT_LE(t.dropped, 0.02);
  EXPECT_EQ(t.merged_objects, 0);
}

// tabletop-realsense 000008 (a D435 at 0.6 m; no labels): the table's refit took in far pieces of the floor and
// the other tables (their tolerance grows with depth) and tilted off the table it started from, so the whole
// near table with the canister, cups and bottle on it became one background segment (docs/RESULTS.md, section
// 15c). The support plane must hold the table and the canister must be an object standing on it.
TEST(Quality, TheRealsenseTableStaysTheSupport) {
  const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "tabletop-realsense";
  const Camera camera = read_camera_json(set / "camera.json");
  const Result r = segment(read_depth_png(set / "depth" / "000008.png"), camera);
  ASSERT_TRUE(r.support_plane);
  int on_plane = 0, valid = 0;  // the bare table below the objects, in front of the canister
  for (int y = 420; y < 470; ++y)
    for (int x = 150; x < 450; ++x) {
      const cv::Vec3f q = r.points.at<cv::Vec3f>(y, x);
      if (!valid_point(q)) continue;
      ++valid;
      on_plane += std::abs(r.support_plane->distance({q[0], q[1], q[2]})) < 0.01f;
    }
  ASSERT_GT(valid, 10000);
  EXPECT_GT(on_plane, 0.9 * valid);
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  const cv::Vec3f canister = r.points.at<cv::Vec3f>(250, 250);  // the wipes canister's front, 10-20 cm high
  ASSERT_TRUE(valid_point(canister));
  EXPECT_GT(r.support_plane->distance({canister[0], canister[1], canister[2]}), 0.05f);
  EXPECT_GT(view.at<int>(250, 250), 0) << "the canister is labelled table or background";
}

// tabletop-realsense 000005 and 000006 (a stereo camera at 0.7-1 m, depth filtered so smooth that a box's
// side is a ramp of 5 cm; no labels): no edge band was left around the objects or along the table's front
// edge, so the table, every object on it and the floor in front were one patch, less than 60 % on one plane;
// the floor became the support and the table with all its objects background: not one object found
// (docs/RESULTS.md, section 22). With support.glued_share the table is the support and the objects are
// cut from it at its plane: each point below, on an object 4-20 cm above the table, is an object's, and
// they are at least `distinct` objects.
TEST(Quality, ObjectsOnATableWhoseEdgesTheDepthSmoothedAway) {
  struct Frame {
    const char* name;
    std::vector<cv::Point> on_objects;
    int distinct;
  };
  const Frame frames[] = {
      {"000005", {{245, 125}, {445, 200}, {130, 90}}, 3},  // two food boxes and a bag
      // canister, R2D2, the box on a container, the mug, a cup, a Lego brick, a food box, a bag
      {"000006", {{150, 120}, {250, 110}, {275, 195}, {365, 300}, {365, 175}, {420, 195}, {510, 225}, {100, 220}}, 6}};
  const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "tabletop-realsense";
  const Camera camera = read_camera_json(set / "camera.json");
  for (const Frame& f : frames) {
    const Result r = segment(read_depth_png(set / "depth" / (std::string(f.name) + ".png")), camera);
    ASSERT_TRUE(r.support_plane) << f.name;
    const cv::Mat view = objects_only(r.object_labels, r.objects);
    std::set<int> objects;
    for (const cv::Point& at : f.on_objects) {
      const cv::Vec3f q = r.points.at<cv::Vec3f>(at);
      ASSERT_TRUE(valid_point(q)) << f.name << " " << at;
      EXPECT_GT(r.support_plane->distance({q[0], q[1], q[2]}), 0.03f) << f.name << " " << at << ": the support is not the table";
      EXPECT_GT(view.at<int>(at), 0) << f.name << " " << at << " is labelled table or background";
      objects.insert(view.at<int>(at));
    }
    objects.erase(0);
    EXPECT_GE(static_cast<int>(objects.size()), f.distinct) << f.name;
  }
}

// tabletop-realsense 000001 and 000002 (no labels): a white bowl seen from above, its far inner wall and its
// floor two patches meeting in a concave crease, were two objects, since a concave crease weighs a link down
// as between two boxes (docs/RESULTS.md, section 24). Both lie on one sphere: one object with
// curvature.inside_crease, two without it.
TEST(Quality, ABowlsWallAndFloorAreOneObject) {
  struct Frame {
    const char* name;
    cv::Point wall, floor;
  };
  const Frame frames[] = {{"000001", {305, 384}, {305, 440}}, {"000002", {420, 230}, {460, 270}}};
  const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "tabletop-realsense";
  const Camera camera = read_camera_json(set / "camera.json");
  Params off;
  off.curvature.inside_crease = false;
  for (const Frame& f : frames) {
    const cv::Mat depth = read_depth_png(set / "depth" / (std::string(f.name) + ".png"));
    const Result r = segment(depth, camera);
    const cv::Mat view = objects_only(r.object_labels, r.objects);
    EXPECT_GT(view.at<int>(f.wall), 0) << f.name << ": the bowl's wall is table or background";
    EXPECT_EQ(view.at<int>(f.wall), view.at<int>(f.floor)) << f.name << ": the bowl's wall and floor are two objects";
    const Result without = segment(depth, camera, off);
    EXPECT_NE(without.object_labels.at<int>(f.wall), without.object_labels.at<int>(f.floor)) << f.name;
  }
  // 000002's teal bowl, a can standing in it: the two halves of its inside are one object, the can another
  // (curvature.split_inside; the halves' centres lie 0.55 of the larger radius apart).
  const Result r = segment(read_depth_png(set / "depth" / "000002.png"), camera);
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  const cv::Point left(260, 210), right(360, 210), can(310, 215);
  EXPECT_GT(view.at<int>(left), 0);
  EXPECT_EQ(view.at<int>(left), view.at<int>(right));
  EXPECT_NE(view.at<int>(left), view.at<int>(can));
}

// tabletop-realsense 000002 (no labels): a can stands on a tin, flush with the tin's front. The can's side and
// the tin's front meet with no crease (filtered stereo depth), and the cut between them and the can's crease
// with the tin's top cost exactly theta_c: one object (docs/RESULTS.md, section 25). With
// convexity.top_angle_deg the can's link to the face below the top's edge is a contact: two objects.
TEST(Quality, ACanOnATinFlushWithItsFrontIsItsOwnObject) {
  const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "tabletop-realsense";
  const Camera camera = read_camera_json(set / "camera.json");
  const cv::Mat depth = read_depth_png(set / "depth" / "000002.png");
  const cv::Point can(140, 200), tin_front(160, 275), tin_top(130, 242);
  const Result r = segment(depth, camera);
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  EXPECT_GT(view.at<int>(can), 0);
  EXPECT_GT(view.at<int>(tin_front), 0);
  EXPECT_NE(view.at<int>(can), view.at<int>(tin_front));
  EXPECT_EQ(view.at<int>(tin_top), view.at<int>(tin_front));
  Params off;
  off.convexity.top_angle_deg = 0;
  const Result without = segment(depth, camera, off);
  EXPECT_EQ(without.object_labels.at<int>(can), without.object_labels.at<int>(tin_front));
}

// tabletop-realsense 000004 (no labels): a round table whose depth lies 6-10 mm off its fitted plane, with bumps
// of stereo noise on it 2-3 mm high; two of them, 116 and 261 px of edge band enclosed by the table, were objects
// (rule 3). With remaining.speck_band they are the table's; the brick, the cup, the can and the canister stay
// objects (docs/RESULTS.md, section 26).
TEST(Quality, BumpsOfNoiseOnARealTableAreNoObjects) {
  const fs::path set = fs::path(CLUTTERSEG_DATA_DIR) / "tabletop-realsense";
  const Camera camera = read_camera_json(set / "camera.json");
  const cv::Mat depth = read_depth_png(set / "depth" / "000004.png");
  const std::vector<cv::Point> specks = {{131, 262}, {43, 327}}, objects = {{260, 260}, {450, 300}, {395, 185}, {230, 150}};
  const Result r = segment(depth, camera);
  const cv::Mat view = objects_only(r.object_labels, r.objects);
  for (const cv::Point& at : specks) EXPECT_EQ(view.at<int>(at), 0) << at << " is an object";
  std::set<int> distinct;
  for (const cv::Point& at : objects) distinct.insert(view.at<int>(at));
  distinct.erase(0);
  EXPECT_EQ(distinct.size(), objects.size());
  Params off;
  off.remaining.speck_band = 0;
  const Result without = segment(depth, camera, off);
  const cv::Mat view_off = objects_only(without.object_labels, without.objects);
  for (const cv::Point& at : specks) EXPECT_GT(view_off.at<int>(at), 0) << at;
}

// The paper's Table II families as `scripts/synth_table2.sh out/table2 20 11` writes them (Kinect v1,
// 640x480, seed 11, 20 frames each), scored as `clutterseg eval` scores them: docs/RESULTS.md, "Synthetic
// scenes with exact labels" (boxes 95.8 / 1.6 / 97.3, stacked boxes 91.4 / 4.6 / 93.6, occluded 88.6 / 5.4 /
// 93.8, cylinders 95.2 / 1.5 / 96.9, mixed 94.8 / 1.6 / 96.5, complex 89.5 / 4.4 / 94.5: tp / fp / Overlap F).
// Issue 14's targets where they are met (tp >= 90, fp <= 5), a point of slack elsewhere.
TEST(Quality, SyntheticTableIIFamilies) {
  struct Family {
    const char* name;
    double min_tp, max_fp;
  };
  const Family families[] = {{"boxes", 0.90, 0.05},    {"stacked-boxes", 0.90, 0.05}, {"occluded", 0.875, 0.065},
                             {"cylinders", 0.90, 0.05}, {"mixed", 0.90, 0.05},         {"complex", 0.88, 0.05}};
  const Camera camera = synth::default_camera();
  Params p;
  p.smoothing.temporal = false;
  for (const Family& family : families) {
    Totals t;
    Segmenter segmenter(p);
    for (int frame = 0; frame < 20; ++frame) {
      const synth::SynthFrame f = synth::synthesize(family.name, 11, frame, camera, synth::Sensor::KinectV1);
      add(t, f.sensor.labels, segmenter.segment(f.sensor.depth_mm, camera));
    }
    average(t);
    EXPECT_GE(t.tp, family.min_tp) << family.name;
    EXPECT_LE(t.fp, family.max_fp) << family.name;
    EXPECT_GE(t.overlap_f, 0.92) << family.name;
    std::printf("%-14s tp %.1f fp %.1f Overlap F %.1f\n", family.name, 100 * t.tp, 100 * t.fp, 100 * t.overlap_f);
  }
}
