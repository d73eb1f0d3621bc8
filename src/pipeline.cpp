// Frames of a stream segmented at once, one per worker (issue 19). The smoothing is the only state
// carried between frames, so it is the one ordered step: a worker runs it for frame n only after frame
// n-1's (a ticket), then segments its frame with a Segmenter whose own smoothing is off - the same
// functions on the same values as Segmenter::segment, so the same labels byte for byte. Object tracking
// (stable ids) is state too: it runs in pop(), in frame order, as at the end of Segmenter::segment.
#include "clutterseg/pipeline.hpp"

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>

#include "clutterseg/limits.hpp"
#include "clutterseg/parallel.hpp"

namespace clutterseg {

namespace {

double ms_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}

}  // namespace

struct Pipeline::State {
  struct Slot {
    std::uint64_t seq = 0;
    cv::Mat depth;
    Camera camera;
    Result result;
    std::exception_ptr error;
    bool new_scene = false;  // the smoothing saw a scene change at this frame: the tracks restart
    bool done = false;
  };

  Params params;
  int workers = 1, capacity = 2;
  std::deque<std::shared_ptr<Slot>> slots;  // in flight, oldest first
  std::uint64_t next_seq = 0;               // the next push
  std::uint64_t next_start = 0;             // the next frame a worker takes
  std::uint64_t front_turn = 0;             // the frame whose smoothing runs next
  TemporalSmoother temporal;
  cv::Mat last_depth;                       // the previous frame, for scene changes without temporal smoothing
  Tracker tracker;                          // used by pop() only, in frame order
  std::mutex tracker_m;
  int active = 0;                           // workers segmenting a frame
  bool adaptive = true;                     // threads = 0: a second frame only on an idle core
  bool stop = false;
  mutable std::mutex m;
  std::condition_variable changed;  // any of the above moved
  std::vector<std::thread> threads;

  std::shared_ptr<Slot> slot_of(std::uint64_t seq) const {
    for (const auto& s : slots)
      if (s->seq == seq) return s;
    return nullptr;
  }

  static Params inner_params(const Params& params) {
    Params inner = params;
    inner.smoothing.median = false;
    inner.smoothing.temporal = false;
    inner.threads = 1;
    inner.tracking.enabled = false;  // pop() tracks, in frame order
    return inner;
  }

  // Smooths the slot's frame in frame order, then segments it with `segmenter`; `lock` (held on entry
  // and exit) is released while working.
  void process(const std::shared_ptr<Slot>& slot, Segmenter& segmenter, std::unique_lock<std::mutex>& lock) {
    // The smoothing, in frame order.
    changed.wait(lock, [&] { return front_turn == slot->seq; });
    cv::Mat smoothed;
    double median_ms = 0, temporal_ms = 0;
    const Params::Smoothing& sp = params.smoothing;
    lock.unlock();  // the ticket alone guards the window
    try {
      auto t = std::chrono::steady_clock::now();
      cv::Mat depth = checked_metres(slot->depth, slot->camera);
      t = std::chrono::steady_clock::now();
      if (sp.median) depth = median_depth(depth);
      median_ms = ms_since(t);
      t = std::chrono::steady_clock::now();
      if (sp.temporal) {
        smoothed = sp.median ? temporal.push(std::move(depth), sp) : temporal.push(depth, sp);
        slot->new_scene = temporal.restarted();
      } else {
        smoothed = depth;
        slot->new_scene = last_depth.empty() || scene_changed(last_depth, depth, sp);
        last_depth = depth;
      }
      temporal_ms = ms_since(t);
    } catch (...) {
      slot->error = std::current_exception();
    }
    lock.lock();
    ++front_turn;
    changed.notify_all();
    if (!slot->error) {
      lock.unlock();
      try {
        Result r = segmenter.segment(smoothed, slot->camera);
        for (auto& [stage, ms] : r.timings_ms) {
          if (stage == "median") ms = median_ms;
          else if (stage == "temporal_smoothing") ms = temporal_ms;
          else if (stage == "total") ms += median_ms + temporal_ms;
        }
        slot->result = std::move(r);
      } catch (...) {
        slot->error = std::current_exception();
      }
      lock.lock();
    }
    slot->depth.release();
    slot->done = true;
  }

  std::unique_ptr<Segmenter> caller_segmenter;  // push()'s own, for frames it segments itself

  void work() {
    set_threads(1);  // the other cores run other frames
    Segmenter segmenter(inner_params(params));
    std::unique_lock lock(m);
    for (;;) {
      // With the default thread count a worker takes a frame while another is busy only if a core is
      // idle: on a loaded machine (another process running) frames go one at a time, as with one
      // thread, and two frames do not share one core's time slices and cache. Re-checked every 2 ms.
      auto may_start = [&] { return active == 0 || !adaptive || free_cores() >= 1; };
      for (;;) {
        changed.wait(lock, [&] { return stop || next_start < next_seq; });
        if (next_start >= next_seq) return;  // stopped with nothing left
        if (may_start()) break;
        changed.wait_for(lock, std::chrono::milliseconds(2));
      }
      ++active;
      process(slot_of(next_start++), segmenter, lock);
      --active;
      changed.notify_all();
    }
  }
};

Pipeline::Pipeline(Params params) : state_(std::make_unique<State>()) {
  validate(params);  // as Segmenter's constructor: every parameter within its range (limits.hpp)
  State& s = *state_;
  if (params.keep_freed_memory) keep_freed_memory();
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  s.workers = params.threads > 0 ? params.threads : cores;
  s.adaptive = params.threads <= 0;
  s.capacity = 2 * s.workers;  // every worker busy, and one frame each waiting
  s.params = std::move(params);
  s.tracker = Tracker(s.params.tracking);
  for (int i = 0; i < s.workers; ++i) s.threads.emplace_back([&s] { s.work(); });
}

Pipeline::~Pipeline() {
  {
    std::lock_guard lock(state_->m);
    state_->stop = true;
  }
  state_->changed.notify_all();
  for (auto& t : state_->threads) t.join();
}

std::uint64_t Pipeline::push(const cv::Mat& depth, const Camera& camera) {
  State& s = *state_;
  std::unique_lock lock(s.m);
  s.changed.wait(lock, [&] { return static_cast<int>(s.slots.size()) < s.capacity; });
  auto slot = std::make_shared<State::Slot>();
  slot->seq = s.next_seq++;
  slot->depth = depth;
  slot->camera = camera;
  s.slots.push_back(slot);
  // Nothing in flight and no idle core for a second frame (another process runs): the caller segments
  // the frame itself, as Segmenter::segment would - no hand-over to a worker, its memory stays warm.
  if (s.adaptive && s.active == 0 && s.next_start + 1 == s.next_seq && free_cores() <= 1) {
    if (!s.caller_segmenter) s.caller_segmenter = std::make_unique<Segmenter>(State::inner_params(s.params));
    ++s.active;
    ++s.next_start;
    s.process(slot, *s.caller_segmenter, lock);
    --s.active;
  }
  s.changed.notify_all();
  return slot->seq;
}

Result Pipeline::pop() {
  State& s = *state_;
  std::unique_lock lock(s.m);
  if (s.slots.empty()) throw Error("Pipeline::pop: no frame in flight");
  const std::shared_ptr<State::Slot> slot = s.slots.front();
  s.changed.wait(lock, [&] { return slot->done; });
  s.slots.pop_front();
  s.changed.notify_all();
  lock.unlock();
  if (slot->error) std::rethrow_exception(slot->error);
  Result r = std::move(slot->result);
  if (s.params.tracking.enabled && !r.object_labels.empty()) {
    const auto t = std::chrono::steady_clock::now();
    std::lock_guard tracking(s.tracker_m);
    if (slot->new_scene) s.tracker.forget();
    r.hidden_objects = s.tracker.update(r.object_labels, r.objects);
    const double ms = ms_since(t);
    for (auto& [stage, value] : r.timings_ms)
      if (stage == "tracking" || stage == "total") value += ms;
  }
  return r;
}

int Pipeline::in_flight() const {
  std::lock_guard lock(state_->m);
  return static_cast<int>(state_->slots.size());
}

int Pipeline::capacity() const { return state_->capacity; }
int Pipeline::workers() const { return state_->workers; }

void Pipeline::reset() {
  State& s = *state_;
  std::unique_lock lock(s.m);
  s.changed.wait(lock, [&] { return s.front_turn == s.next_seq; });
  s.temporal.reset();
  s.last_depth.release();
  std::lock_guard tracking(s.tracker_m);
  s.tracker.reset();
}

}  // namespace clutterseg
