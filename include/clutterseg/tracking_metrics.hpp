// Tracking quality over a sequence whose ground-truth ids follow each object (docs/EVAL.md, Tracking):
// does a predicted object keep its id from frame to frame, and is an id ever given to another object?
#pragma once

#include <limits>
#include <map>
#include <set>

#include "clutterseg/types.hpp"

namespace clutterseg {

struct TrackingScores {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  long object_frames = 0;    // (ground-truth object, frame) pairs: each object in each frame it is visible
  long matched = 0;          // of them matched to a predicted object (IoU > 0.5, so one-to-one)
  long steps = 0;            // matched object-frames of an object matched in an earlier frame of the sequence
  long kept = 0;             // of them with the predicted id of the object's previous match
  long switches = 0;         // steps - kept
  long false_positives = 0;  // predicted objects matched to no ground-truth object, summed over frames
  long objects = 0;          // distinct ground-truth objects
  long reused_ids = 0;       // predicted ids matched to more than one ground-truth object in a sequence
  long frames = 0;

  double id_kept() const { return steps > 0 ? static_cast<double>(kept) / static_cast<double>(steps) : kNaN; }
  // Id switches per object per 100 frames: per 100 object-frames.
  double switches_per_100() const { return object_frames > 0 ? 100.0 * static_cast<double>(switches) / static_cast<double>(object_frames) : kNaN; }
  // CLEAR-MOT accuracy: 1 - (missed + false positives + id switches) / object-frames.
  double mota() const {
    return object_frames > 0 ? 1.0 - static_cast<double>((object_frames - matched) + false_positives + switches) /
                                         static_cast<double>(object_frames)
                             : kNaN;
  }
  TrackingScores& operator+=(const TrackingScores& o);
};

// Feeds the frames of one sequence in order (one scorer per sequence).
class TrackingScorer {
 public:
  // Label images of one frame, CV_32S/CV_16U/CV_8U, 0 = no object on both sides. Throws Error when the two
  // differ in size or are not single-channel integer images.
  void add(const cv::Mat& ground_truth, const cv::Mat& prediction);
  const TrackingScores& scores() const { return scores_; }

 private:
  std::map<int, int> last_id_;               // ground-truth id -> predicted id at its last match
  std::map<int, std::set<int>> objects_of_;  // predicted id -> ground-truth ids it was matched to
  std::set<int> seen_;
  TrackingScores scores_;
};

}  // namespace clutterseg
