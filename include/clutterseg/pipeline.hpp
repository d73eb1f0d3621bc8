// Throughput over a stream: consecutive frames segmented at once on several cores (issue 19).
#pragma once

#include <cstdint>
#include <memory>

#include "clutterseg/segmenter.hpp"

namespace clutterseg {

// A stream of frames in, their Results out in the same order, with the labels Segmenter gives for the
// same frames (byte for byte). The smoothing (3x3 median, temporal window) is the only state carried from
// frame to frame with the object tracks: both run once per frame in frame order (tracking in pop()); the stages after it (normals to objects) run
// for several frames at once, one frame per worker thread. This raises frames per second, not the
// latency of a frame (for that, Segmenter's row parallelism). Workers = Params::threads (0 = one per
// core); each frame's own rows run serially. On a busy machine the workers get what share of the cores
// the scheduler gives them, and never wait on each other (docs/BENCHMARKS.md "Threads").
class Pipeline {
 public:
  explicit Pipeline(Params params = {});
  ~Pipeline();  // finishes the frames in flight
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Queues a frame (the image is shared, not copied: do not write to it until its result is popped).
  // Blocks while `capacity()` frames are in flight. Returns the frame's sequence number (0, 1, ...).
  std::uint64_t push(const cv::Mat& depth, const Camera& camera);
  // The oldest frame's Result; blocks until it is done. Rethrows the frame's Error (bad depth or
  // intrinsics) instead; the temporal window then never saw that frame, as with Segmenter.
  Result pop();
  // Frames pushed and not yet popped.
  int in_flight() const;
  int capacity() const;
  int workers() const;
  void reset();  // clears the temporal window (waits for the frames in flight first)

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace clutterseg
