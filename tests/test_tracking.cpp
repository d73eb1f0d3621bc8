// The tracker alone, on object lists and label images built by hand: what a user of a stream reads.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>

#include "clutterseg/objects.hpp"
#include "clutterseg/tracking.hpp"
#include "clutterseg/tracking_metrics.hpp"

namespace clutterseg {
namespace {

// One object of a hand-made frame: an image rectangle and a 3D position/size.
struct Blob {
  cv::Rect rect;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  Eigen::Vector3f extents = Eigen::Vector3f(0.05f, 0.05f, 0.05f);
};

// A blob in a 1 px = 1 mm world at 1 m: x, y in pixels, the centroid follows the rectangle's centre.
Blob blob(int x, int y, int w, int h, float depth = 1.0f) {
  Blob b;
  b.rect = cv::Rect(x, y, w, h);
  b.centroid = Eigen::Vector3f((x + w / 2.f) * 0.001f, (y + h / 2.f) * 0.001f, depth);
  b.extents = Eigen::Vector3f(w * 0.001f, h * 0.001f, 0.04f);
  return b;
}

struct Frame {
  cv::Mat labels;
  std::vector<Object> objects;
};

// Labels k + 1 for blobs[k] (later blobs drawn over earlier ones), objects as the pipeline makes them.
Frame make_frame(const std::vector<Blob>& blobs, cv::Size size = {320, 240}) {
  Frame f;
  f.labels = cv::Mat(size, CV_32S, cv::Scalar(0));
  for (size_t k = 0; k < blobs.size(); ++k) f.labels(blobs[k].rect & cv::Rect({}, size)).setTo(static_cast<int>(k) + 1);
  for (size_t k = 0; k < blobs.size(); ++k) {
    Object o;
    o.id = static_cast<int>(k) + 1;
    o.pixel_count = cv::countNonZero(f.labels == o.id);
    o.centroid = blobs[k].centroid;
    o.box.center = blobs[k].centroid;
    o.box.extents = blobs[k].extents;
    f.objects.push_back(o);
  }
  return f;
}

// The id the tracker gave to the pixel at the centre of `b`.
int id_at(const Frame& f, const Blob& b) {
  return f.labels.at<int>(b.rect.y + b.rect.height / 2, b.rect.x + b.rect.width / 2);
}

const Object* object_with(const Frame& f, int id) {
  for (const Object& o : f.objects)
    if (o.id == id) return &o;
  return nullptr;
}

// Runs blobs through the tracker; returns the tracked frame.
Frame step(Tracker& tracker, const std::vector<Blob>& blobs, std::vector<HiddenObject>* hidden = nullptr) {
  Frame f = make_frame(blobs);
  auto h = tracker.update(f.labels, f.objects);
  if (hidden) *hidden = h;
  return f;
}

TEST(Tracking, FirstFrameNumbersObjectsInOrder) {
  Tracker tracker;
  const Frame f = step(tracker, {blob(10, 10, 40, 40), blob(100, 10, 40, 40), blob(200, 100, 30, 60)});
  ASSERT_EQ(f.objects.size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(f.objects[k].id, static_cast<int>(k) + 1);
    EXPECT_EQ(f.objects[k].age, 1);
  }
  EXPECT_EQ(f.labels.at<int>(30, 30), 1);
  EXPECT_EQ(f.labels.at<int>(130, 215), 3);
}

TEST(Tracking, StaticObjectsKeepTheirIdsWhateverOrderTheSegmenterNumbersThem) {
  Tracker tracker;
  std::vector<Blob> blobs = {blob(10, 10, 40, 40), blob(100, 10, 40, 40), blob(200, 100, 30, 60), blob(20, 150, 80, 30)};
  const Frame first = step(tracker, blobs);
  std::map<int, int> id_of;  // blob -> id
  for (int k = 0; k < 4; ++k) id_of[k] = id_at(first, blobs[static_cast<size_t>(k)]);
  std::vector<int> order = {0, 1, 2, 3};
  for (int frame = 2; frame <= 20; ++frame) {
    std::rotate(order.begin(), order.begin() + 1, order.end());  // the pipeline numbers them differently
    std::vector<Blob> shuffled;
    for (int k : order) shuffled.push_back(blobs[static_cast<size_t>(k)]);
    const Frame f = step(tracker, shuffled);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(id_at(f, blobs[static_cast<size_t>(k)]), id_of[k]) << "frame " << frame;
    for (size_t i = 1; i < f.objects.size(); ++i) EXPECT_LT(f.objects[i - 1].id, f.objects[i].id);  // sorted by id
    ASSERT_NE(object_with(f, id_of[0]), nullptr);
    EXPECT_EQ(object_with(f, id_of[0])->age, frame);
    EXPECT_EQ(object_with(f, id_of[0])->frames_missed, 0);
  }
}

TEST(Tracking, AMovingObjectKeepsItsId) {
  Tracker tracker;
  int id = 0;
  for (int frame = 0; frame < 40; ++frame) {
    const Blob mover = blob(10 + 6 * frame, 50, 40, 40);  // 6 mm per frame across a static one
    const Blob still = blob(150, 150, 50, 50);
    const Frame f = step(tracker, {still, mover});
    if (frame == 0) id = id_at(f, mover);
    EXPECT_EQ(id_at(f, mover), id) << "frame " << frame;
  }
}

TEST(Tracking, ANewObjectGetsAnIdNeverUsedBefore) {
  Params::Tracking p;
  p.max_missed = 2;
  Tracker tracker(p);
  std::set<int> seen;
  for (int frame = 0; frame < 30; ++frame) {
    // Every 3 frames one object is taken away and another one put down somewhere else.
    const int k = frame / 3;
    const Frame f = step(tracker, {blob(10, 10, 40, 40), blob(60 + (k % 5) * 45, 120 + (k % 2) * 60, 30, 30, 1.0f + 0.1f * k)});
    const int id = id_at(f, blob(60 + (k % 5) * 45, 120 + (k % 2) * 60, 30, 30));
    if (frame % 3 == 0) {
      EXPECT_FALSE(seen.count(id)) << "frame " << frame << ": id " << id << " was used before";
      seen.insert(id);
    } else {
      EXPECT_TRUE(seen.count(id));
    }
  }
}

TEST(Tracking, AnObjectHiddenForAFewFramesGetsItsIdBack) {
  Params::Tracking p;
  p.max_missed = 10;
  Tracker tracker(p);
  const Blob a = blob(20, 20, 40, 40), b = blob(150, 60, 40, 40);
  const Frame first = step(tracker, {a, b});
  const int id_b = id_at(first, b);
  std::vector<HiddenObject> hidden;
  for (int frame = 1; frame <= 6; ++frame) {
    step(tracker, {a}, &hidden);  // b hidden (behind a hand, say)
    ASSERT_EQ(hidden.size(), 1u);
    EXPECT_EQ(hidden[0].id, id_b);
    EXPECT_EQ(hidden[0].frames_since_seen, frame);
    EXPECT_EQ(hidden[0].merged_into, 0);
  }
  const Frame back = step(tracker, {blob(152, 61, 40, 40), a}, &hidden);
  EXPECT_EQ(id_at(back, b), id_b);
  EXPECT_EQ(object_with(back, id_b)->frames_missed, 6);
  EXPECT_EQ(object_with(back, id_b)->age, 8);
  EXPECT_TRUE(hidden.empty());
}

TEST(Tracking, AnObjectPassingBehindAnotherIsFollowedByItsVelocity) {
  Tracker tracker;
  const Blob occluder = blob(140, 40, 40, 120, 0.8f);
  int id = 0;
  for (int frame = 0; frame < 34; ++frame) {  // out of the 320 px image after that
    Blob mover = blob(20 + 8 * frame, 80, 30, 30);  // 8 mm per frame, behind the occluder for ~8 frames
    std::vector<Blob> blobs = {occluder};
    const cv::Rect visible = mover.rect;
    const bool behind = visible.x + visible.width > 140 && visible.x < 180;
    if (!behind) blobs.push_back(mover);
    const Frame f = step(tracker, blobs);
    if (frame == 0) id = id_at(f, mover);
    if (!behind) EXPECT_EQ(id_at(f, mover), id) << "frame " << frame;
  }
}

TEST(Tracking, AMergeForAFrameKeepsBothIds) {
  Tracker tracker;
  const Blob a = blob(40, 40, 40, 40), b = blob(82, 40, 40, 40);
  const Frame f0 = step(tracker, {a, b});
  const int id_a = id_at(f0, a), id_b = id_at(f0, b);
  // One frame the segmenter sees one object where there were two (they touch).
  std::vector<HiddenObject> hidden;
  const Frame merged = step(tracker, {blob(40, 40, 82, 40)}, &hidden);
  ASSERT_EQ(merged.objects.size(), 1u);
  const Object& host = merged.objects[0];
  EXPECT_TRUE(host.id == id_a || host.id == id_b);
  const int guest = host.id == id_a ? id_b : id_a;
  EXPECT_EQ(host.merged_with, std::vector<int>{guest});
  ASSERT_EQ(hidden.size(), 1u);
  EXPECT_EQ(hidden[0].id, guest);
  EXPECT_EQ(hidden[0].merged_into, host.id);
  // Apart again: both ids where they were.
  const Frame apart = step(tracker, {b, a}, &hidden);
  EXPECT_EQ(id_at(apart, a), id_a);
  EXPECT_EQ(id_at(apart, b), id_b);
  EXPECT_TRUE(hidden.empty());
  for (const Object& o : apart.objects) EXPECT_TRUE(o.merged_with.empty());
}

TEST(Tracking, ASplitForAFrameKeepsTheIdOnTheLargerPartAndDropsTheFragmentAfterwards) {
  Tracker tracker;
  const Blob whole = blob(40, 40, 100, 40);
  const int id = id_at(step(tracker, {whole}), whole);
  std::vector<HiddenObject> hidden;
  const Blob big = blob(40, 40, 70, 40), small = blob(112, 40, 28, 40);
  const Frame split = step(tracker, {small, big}, &hidden);
  EXPECT_EQ(id_at(split, big), id);
  const int fragment = id_at(split, small);
  EXPECT_GT(fragment, id);
  EXPECT_EQ(object_with(split, fragment)->split_from, id);
  const Frame rejoined = step(tracker, {whole}, &hidden);
  EXPECT_EQ(id_at(rejoined, whole), id);
  EXPECT_TRUE(hidden.empty()) << "the fragment merged back into the object it split from is dropped";
  EXPECT_TRUE(rejoined.objects[0].merged_with.empty());
}

TEST(Tracking, AnObjectGoneLongerThanMaxMissedIsForgotten) {
  Params::Tracking p;
  p.max_missed = 3;
  Tracker tracker(p);
  const Blob a = blob(20, 20, 40, 40), b = blob(150, 60, 40, 40);
  const int id_b = id_at(step(tracker, {a, b}), b);
  std::vector<HiddenObject> hidden;
  for (int frame = 1; frame <= 4; ++frame) step(tracker, {a}, &hidden);
  EXPECT_TRUE(hidden.empty());
  const int again = id_at(step(tracker, {a, b}), b);
  EXPECT_NE(again, id_b);
  EXPECT_GT(again, id_b);
}

TEST(Tracking, IdsWrapAtMaxIdAndSkipIdsInUse) {
  Params::Tracking p;
  p.max_missed = 0;
  p.max_id = 5;
  Tracker tracker(p);
  const Blob still = blob(10, 10, 30, 30);
  const int id_still = id_at(step(tracker, {still}), still);
  for (int frame = 0; frame < 20; ++frame) {
    // A new object every frame at a place far from the last one (never matched).
    const Blob b = blob(100 + (frame % 2) * 120, 100, 30, 30, 1.0f + 0.5f * frame);
    const Frame f = step(tracker, {still, b});
    EXPECT_EQ(id_at(f, still), id_still);
    const int id = id_at(f, b);
    EXPECT_GE(id, 1);
    EXPECT_LE(id, 5);
    EXPECT_NE(id, id_still);
  }
}

TEST(Tracking, ForgetKeepsCountingAndResetStartsAgain) {
  Tracker tracker;
  const Blob a = blob(20, 20, 40, 40), b = blob(150, 60, 40, 40);
  step(tracker, {a, b});
  tracker.forget();  // a new scene: the same place is another object
  const Frame f = step(tracker, {a, b});
  EXPECT_EQ(id_at(f, a), 3);
  EXPECT_EQ(id_at(f, b), 4);
  tracker.reset();
  const Frame g = step(tracker, {b, a});
  EXPECT_EQ(id_at(g, b), 1);
  EXPECT_EQ(id_at(g, a), 2);
}

TEST(Tracking, AnotherObjectAppearingWhereOneWasRemovedGetsANewId) {
  Tracker tracker;
  const Blob a = blob(100, 100, 40, 40, 0.8f);
  const int id_a = id_at(step(tracker, {a}), a);
  // a is lifted away; behind it, 20 cm deeper, another object is revealed at the same pixels.
  const Blob behind = blob(100, 100, 40, 40, 1.0f);
  const Frame f = step(tracker, {behind});
  EXPECT_NE(id_at(f, behind), id_a);
}

// Two objects side by side; `left` and `right` are the ids written on them (0 = not there).
cv::Mat two(int left, int right) {
  cv::Mat m(20, 40, CV_32S, cv::Scalar(0));
  m(cv::Rect(2, 2, 15, 15)).setTo(left);
  m(cv::Rect(22, 2, 15, 15)).setTo(right);
  return m;
}

TEST(TrackingScores, CountKeptStepsSwitchesAndReusedIds) {
  TrackingScorer scorer;
  scorer.add(two(1, 2), two(10, 20));
  scorer.add(two(1, 2), two(10, 20));  // both kept
  scorer.add(two(1, 2), two(10, 0));   // 2 missed: no step for it
  scorer.add(two(1, 2), two(10, 20));  // 2 back with its id: kept
  scorer.add(two(1, 2), two(20, 10));  // swapped: two switches, both ids now name two objects
  const TrackingScores& s = scorer.scores();
  EXPECT_EQ(s.frames, 5);
  EXPECT_EQ(s.objects, 2);
  EXPECT_EQ(s.object_frames, 10);
  EXPECT_EQ(s.matched, 9);
  EXPECT_EQ(s.steps, 7);
  EXPECT_EQ(s.kept, 5);
  EXPECT_EQ(s.switches, 2);
  EXPECT_EQ(s.reused_ids, 2);
  EXPECT_DOUBLE_EQ(s.id_kept(), 5.0 / 7.0);
  EXPECT_DOUBLE_EQ(s.switches_per_100(), 20.0);
  EXPECT_DOUBLE_EQ(s.mota(), 1.0 - (1 + 0 + 2) / 10.0);
}

TEST(TrackingScores, AWeakOverlapIsNoMatch) {
  TrackingScorer scorer;
  cv::Mat gt = two(1, 0), pred(20, 40, CV_32S, cv::Scalar(0));
  pred(cv::Rect(2, 2, 7, 15)).setTo(5);  // less than half of object 1
  scorer.add(gt, pred);
  EXPECT_EQ(scorer.scores().matched, 0);
  EXPECT_EQ(scorer.scores().false_positives, 1);
  EXPECT_THROW(scorer.add(gt, cv::Mat(10, 10, CV_32S, cv::Scalar(0))), Error);
}

TEST(Tracking, TheObjectsOnlyViewKeepsTrackedIds) {
  cv::Mat labels(4, 3, CV_32S, cv::Scalar(0));
  labels.row(0).setTo(3);
  labels.row(1).setTo(7);
  labels.row(2).setTo(9);
  std::vector<Object> objects(3);
  objects[0].id = 3;
  objects[1].id = 7;
  objects[1].support = true;
  objects[2].id = 9;
  const cv::Mat kept = objects_only(labels, objects, true), renumbered = objects_only(labels, objects);
  EXPECT_EQ(kept.at<int>(0, 0), 3);
  EXPECT_EQ(kept.at<int>(1, 0), 0);
  EXPECT_EQ(kept.at<int>(2, 0), 9);
  EXPECT_EQ(renumbered.at<int>(0, 0), 1);
  EXPECT_EQ(renumbered.at<int>(2, 0), 2);
}

TEST(Tracking, RejectsLabelsThatAreNotInt32) {
  Tracker tracker;
  cv::Mat labels(10, 10, CV_16U, cv::Scalar(0));
  std::vector<Object> objects;
  EXPECT_THROW(tracker.update(labels, objects), Error);
}

}  // namespace
}  // namespace clutterseg
