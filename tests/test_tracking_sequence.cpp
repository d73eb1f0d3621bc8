// Tracking through the whole pipeline on synthetic streams with exact ids (Kinect v1 noise, 320x240 to keep
// the suite fast): the `sequence` and `pick-and-place` presets, and the pick-and-place timeline itself.
#include <gtest/gtest.h>

#include <cstdio>
#include <set>

#include "clutterseg/objects.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/synth/dataset.hpp"
#include "clutterseg/tracking_metrics.hpp"

using namespace clutterseg;

namespace {

TrackingScores track(const std::string& preset, std::uint64_t seed, int frames, bool tracking = true) {
  const Camera camera = synth::default_camera(320, 240);
  Params params;
  params.tracking.enabled = tracking;
  Segmenter segmenter(params);
  TrackingScorer scorer;
  for (int i = 0; i < frames; ++i) {
    const synth::SynthFrame f = synth::synthesize(preset, seed, i, camera, synth::Sensor::KinectV1);
    const Result r = segmenter.segment(f.sensor.depth, camera);
    scorer.add(f.sensor.labels, objects_only(r.object_labels, r.objects, tracking));
  }
  const TrackingScores& s = scorer.scores();
  std::printf("%s seed %llu%s: %ld object-frames, %ld matched, id kept %.2f %%, %ld switches, %ld ids reused\n",
              preset.c_str(), static_cast<unsigned long long>(seed), tracking ? "" : " (no tracking)", s.object_frames,
              s.matched, 100 * s.id_kept(), s.switches, s.reused_ids);
  return s;
}

}  // namespace

TEST(TrackingSequence, PickAndPlaceRemovesCarriesAndSlidesObjectsWithTheirIds) {
  const Camera camera = synth::default_camera(320, 240);
  std::set<int> ids_at_start, ids_at_end;
  for (const auto& o : synth::generate_scene("pick-and-place", 5, 0, camera).objects) ids_at_start.insert(o.id);
  for (const auto& o : synth::generate_scene("pick-and-place", 5, 59, camera).objects) ids_at_end.insert(o.id);
  EXPECT_EQ(ids_at_start, (std::set<int>{1, 2, 3, 4, 5}));
  EXPECT_EQ(ids_at_end, (std::set<int>{1, 2, 4}));  // 3 and 5 were lifted away; their ids are not reused
  const auto pose = [&](int frame, int id) -> Eigen::Vector3d {
    for (const auto& o : synth::generate_scene("pick-and-place", 5, frame, camera).objects)
      if (o.id == id) return o.pose.translation();
    ADD_FAILURE() << "no object " << id << " in frame " << frame;
    return Eigen::Vector3d::Zero();
  };
  EXPECT_GT((pose(59, 4) - pose(0, 4)).norm(), 0.25);  // carried and put down elsewhere
  EXPECT_NEAR(pose(59, 4).z(), pose(0, 4).z(), 1e-9);   // resting again
  EXPECT_GT((pose(59, 2) - pose(0, 2)).norm(), 0.3);    // slid behind the tall box
  EXPECT_NEAR((pose(59, 1) - pose(0, 1)).norm(), 0, 1e-9);
  bool held = false;
  for (const auto& o : synth::generate_scene("pick-and-place", 5, 20, camera).objects) held = held || (o.id == 4 && o.held);
  EXPECT_TRUE(held);
  // The camera sways a little, by at most 2.5 mm a frame.
  for (int frame = 1; frame < 60; frame += 7) {
    const double step = (synth::generate_scene("pick-and-place", 5, frame, camera).eye -
                         synth::generate_scene("pick-and-place", 5, frame - 1, camera).eye).norm();
    EXPECT_GT(step, 0.0);
    EXPECT_LT(step, 0.0025);
  }
}

TEST(TrackingSequence, IdsAreKeptOnTheSyntheticStreams) {
  for (const char* preset : {"sequence", "pick-and-place"}) {
    const TrackingScores s = track(preset, 1, 60);
    EXPECT_GT(s.steps, 150) << preset;
    EXPECT_GE(s.id_kept(), 0.99) << preset;
    EXPECT_EQ(s.reused_ids, 0) << preset;
  }
}

TEST(TrackingSequence, WithoutTrackingIdsAreNumberedAfreshEveryFrame) {
  const Camera camera = synth::default_camera(320, 240);
  Params params;
  params.tracking.enabled = false;
  Segmenter segmenter(params);
  for (int i = 0; i < 3; ++i) {
    const synth::SynthFrame f = synth::synthesize("pick-and-place", 2, i, camera, synth::Sensor::KinectV1);
    const Result r = segmenter.segment(f.sensor.depth, camera);
    for (size_t k = 0; k < r.objects.size(); ++k) {
      EXPECT_EQ(r.objects[k].id, static_cast<int>(k) + 1);
      EXPECT_EQ(r.objects[k].age, 1);
    }
    EXPECT_TRUE(r.hidden_objects.empty());
  }
}
