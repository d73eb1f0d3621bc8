// Beyond the paper: stable object ids across the frames of a stream (docs/TRACKING.md). The tracker only
// renames: it never changes which pixels form an object, it gives each object the id it had before.
#pragma once

#include <cstdint>
#include <vector>

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

// An object the tracker remembers but does not see in this frame: occluded, gone for a while, or merged
// into a visible object (merged_into). Forgotten after Params::Tracking::max_missed frames unseen.
struct HiddenObject {
  int id = 0;
  int age = 0;                // frames since it was first seen (1 on that frame)
  int frames_since_seen = 0;  // >= 1
  int merged_into = 0;        // id of the visible object it merged with, 0 = none (just not seen)
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();  // where it was last seen (Object::centroid's frame)
  OrientedBox box;            // its box when last seen
};

// Frame-to-frame matching of objects (docs/TRACKING.md, rules 1-5). Per frame, in this order:
//  1. overlap: pairs (object of the previous frame, object of this frame) that share pixels, on a grid of
//     160 columns, by IoU, greatest first, within a 3D gate around the track's predicted centroid;
//  2. merge: an unmatched previous object mostly inside (or, moving, with its predicted centroid inside
//     the box of) an object that kept another id is merged into it; the merged object carries the larger
//     one's id (Object::merged_with, HiddenObject::merged_into); the table and background host nothing;
//  3. split: a host that comes apart gives its parts to itself and its guests by 3D distance; another
//     unmatched part of an object that kept its id gets a new id with Object::split_from, dropped when it
//     merges back;
//  4. return: the rest are matched to remembered objects by 3D distance to the predicted centroid
//     (constant velocity), nearest first, gate growing with sqrt(frames unseen), no larger than the
//     remembered object;
//  5. new: every object still unmatched gets an id never used in the stream (ids wrap at max_id, skipping
//     ids still in use).
class Tracker {
 public:
  explicit Tracker(const Params::Tracking& params = {}) : params_(params) {}

  // labels: CV_32S, object k has label k + 1 (objects[k].id == k + 1, as the pipeline makes them).
  // Rewrites labels and every Object's id, age, frames_missed, split_from and merged_with in place,
  // sorts objects by id, and returns the remembered objects not seen in this frame (sorted by id).
  std::vector<HiddenObject> update(cv::Mat& labels, std::vector<Object>& objects);

  // A new scene (scene_changed): every track is dropped, ids still count on (never reused).
  void forget();
  // A new stream: also restarts ids at 1.
  void reset();

  int frame() const { return frame_; }
  int tracks() const { return static_cast<int>(tracks_.size()); }

 private:
  struct Track {
    int id = 0, first_frame = 0, last_seen = 0;
    int merged_into = 0, split_from = 0;
    int pixels = 0;
    Eigen::Vector3f centroid = Eigen::Vector3f::Zero(), velocity = Eigen::Vector3f::Zero();
    Eigen::Vector3f seen = Eigen::Vector3f::Zero();  // centroid of the object that last carried its id
    bool hosting = false;                            // carried the id of a merge in the last frame seen
    Eigen::Vector3f extents = Eigen::Vector3f::Zero();  // box extents, largest first
    OrientedBox box;
    float diagonal = 0;
  };
  int new_id();
  Params::Tracking params_;
  std::vector<Track> tracks_;        // sorted by id
  std::vector<int> previous_grid_;   // previous frame's object k + 1 per grid pixel, 0 = none
  std::vector<int> previous_ids_;    // track id of previous object k
  cv::Size size_;                    // of the previous frame's labels
  int frame_ = 0;
  int next_id_ = 1;
};

}  // namespace clutterseg
