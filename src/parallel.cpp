// Row parallelism that never loses to one thread (issue 19, docs/BENCHMARKS.md "Threads").
//
// OpenMP's `parallel for` lost on the 2-core machine: libgomp's idle threads spin (OMP_WAIT_POLICY is read
// once, before main, so a library cannot change it), and with `schedule(static)` the caller waits at the
// end of every region for the other thread's half of the rows, which on a busy core is a scheduler time
// slice away: 140 ms per frame against 30 ms for one thread. Here instead:
// - helpers sleep on a condition variable between regions (after a 30 us spin that bridges the gaps
//   between the regions of one stage), so they take no core from anyone when idle;
// - rows are claimed in blocks from an atomic counter and the caller works too, so a helper that is late
//   (its core busy) simply finds no block left; the caller waits only for blocks a helper has started;
// - with the default thread count (0) a region runs on as many threads as there are idle cores right now
//   (runnable tasks from /proc/loadavg, re-read every 10 ms): one thread when the machine is busy.
// The split never changes what a row computes, so the output is identical for any thread count.
#include "clutterseg/parallel.hpp"

#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace clutterseg {

namespace {

using Clock = std::chrono::steady_clock;

thread_local int t_threads = 0;  // the calling thread's request (set_threads); 0 = adaptive

int cores() {
  static const int n = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return n;
}

// Runnable tasks on the whole machine (the caller included), from the 4th field of /proc/loadavg
// ("running/total"); -1 when unknown (not Linux).
int runnable_tasks() {
  std::FILE* f = std::fopen("/proc/loadavg", "r");
  if (!f) return -1;
  double a, b, c;
  int running = -1, total = 0;
  if (std::fscanf(f, "%lf %lf %lf %d/%d", &a, &b, &c, &running, &total) != 5) running = -1;
  std::fclose(f);
  return running;
}

}  // namespace

int free_cores() {
  const int running = runnable_tasks();
  return running < 0 ? cores() : cores() - running + 1;
}

namespace {

// free_cores(), clamped to [1, cores], re-read at most every 10 ms (a read costs a few microseconds; a
// frame has ~10 regions).
int cached_free_cores() {
  constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();
  static std::atomic<std::int64_t> read_at{kNever};
  static std::atomic<int> cached{1};
  const std::int64_t now = Clock::now().time_since_epoch().count();
  constexpr std::int64_t kRefresh = std::chrono::duration_cast<Clock::duration>(std::chrono::milliseconds(10)).count();
  std::int64_t last = read_at.load(std::memory_order_relaxed);
  if ((last == kNever || now - last >= kRefresh) && read_at.compare_exchange_strong(last, now))  // no overflow
    cached.store(std::clamp(free_cores(), 1, cores()), std::memory_order_relaxed);
  return cached.load(std::memory_order_relaxed);
}

// One region: blocks [0, blocks) of kBlock rows, claimed one at a time.
struct Job {
  const std::function<void(int, int)>* body = nullptr;
  int rows = 0, blocks = 0, block = 16;
  std::atomic<int> next{0}, finished{0};
  std::mutex m;
  std::condition_variable cv;

  // Claims and runs blocks until none is left; a claim past the end never touches `body`, so a late
  // helper holding this job after the caller returned does nothing.
  std::exception_ptr error;  // the first block's exception, rethrown by the caller after every block ended

  void work() {
    for (int b = next.fetch_add(1); b < blocks; b = next.fetch_add(1)) {
      const int begin = b * block;
      try {
        (*body)(begin, std::min(rows, begin + block));
      } catch (...) {
        std::lock_guard lock(m);
        if (!error) error = std::current_exception();
      }
      if (finished.fetch_add(1) + 1 == blocks) {
        std::lock_guard lock(m);
        cv.notify_all();
      }
    }
  }
};

class Pool {
 public:
  static Pool& get() {
    static Pool pool;  // helpers start on the first parallel region
    return pool;
  }

  // Runs the job on the caller and up to `helpers` pool threads; false when another caller is running
  // a region (then the caller runs it alone).
  bool run(const std::shared_ptr<Job>& job, int helpers) {
    std::unique_lock region(region_, std::try_to_lock);
    if (!region.owns_lock()) return false;
    {
      std::lock_guard lock(m_);
      if (threads_.empty())
        for (int i = 1; i < cores(); ++i) threads_.emplace_back([this] { loop(); });
      job_ = job;
      wanted_ = std::min(helpers, static_cast<int>(threads_.size()));
      taken_ = 0;
      ++generation_;
    }
    for (int i = 0; i < wanted_; ++i) wake_.notify_one();
    job->work();
    // Wait for blocks a helper has started: a short spin, then sleep.
    const auto spin_until = Clock::now() + std::chrono::microseconds(30);
    while (job->finished.load() < job->blocks && Clock::now() < spin_until) std::this_thread::yield();
    if (job->finished.load() < job->blocks) {
      std::unique_lock lock(job->m);
      job->cv.wait(lock, [&] { return job->finished.load() >= job->blocks; });
    }
    {
      std::lock_guard lock(m_);
      job_.reset();  // helpers that wake now see no job
    }
    if (job->error) std::rethrow_exception(job->error);  // the body is not in use any more
    return true;
  }

  ~Pool() {
    {
      std::lock_guard lock(m_);
      stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
  }

 private:
  void loop() {
    std::uint64_t seen = 0;
    for (;;) {
      // Spin briefly for the next region of the same stage, then sleep.
      const auto spin_until = Clock::now() + std::chrono::microseconds(30);
      while (generation_.load() == seen && !stop_.load() && Clock::now() < spin_until) std::this_thread::yield();
      std::shared_ptr<Job> job;
      {
        std::unique_lock lock(m_);
        wake_.wait(lock, [&] { return stop_.load() || generation_.load() != seen; });
        if (stop_) return;
        seen = generation_;
        if (job_ && taken_ < wanted_) {
          ++taken_;
          job = job_;
        }
      }
      if (job) job->work();
    }
  }

  std::mutex region_;  // one region at a time; a second caller runs alone
  std::mutex m_;
  std::condition_variable wake_;
  std::vector<std::thread> threads_;
  std::shared_ptr<Job> job_;
  std::atomic<std::uint64_t> generation_{0};
  int wanted_ = 0, taken_ = 0;
  std::atomic<bool> stop_{false};
};

}  // namespace

void set_threads(int threads) {
  // OpenCV's calls here (median, Gaussian, components) are short; its pool's idle threads spin and
  // took the cores our rows needed (2 threads ran 4x slower than 1), so OpenCV stays serial. Set once:
  // cv::setNumThreads is a process-wide setting and not safe to call from threads at once (TSan: a race
  // inside TBB when three Segmenters started together).
  static std::once_flag opencv_serial;
  std::call_once(opencv_serial, [] { cv::setNumThreads(1); });
  t_threads = std::max(0, threads);
}

int region_threads() {
  if (t_threads == 1 || cores() == 1) return 1;
  if (t_threads > 1) return std::min(t_threads, cores());
  // The default leaves one idle core alone: rows over the 2 cores of our test host never paid (0.95-1.05x
  // one thread, docs/BENCHMARKS.md "Threads"), while another frame (Pipeline), the sensor driver or the
  // robot's own work gains a whole core. With 3 or more idle cores the rows spread over all but one.
  return std::max(1, cached_free_cores() - 1);
}

void parallel_for_rows(int rows, const std::function<void(int, int)>& body) {
  // Blocks of rows amortise the claim; the split never changes what each row computes.
  constexpr int kBlock = 16;
  const int blocks = (rows + kBlock - 1) / kBlock;
  const int threads = blocks > 1 ? std::min(region_threads(), blocks) : 1;
  if (threads > 1) {
    auto job = std::make_shared<Job>();
    job->body = &body;
    job->rows = rows;
    job->blocks = blocks;
    job->block = kBlock;
    if (Pool::get().run(job, threads - 1)) return;
  }
  for (int begin = 0; begin < rows; begin += kBlock) body(begin, std::min(rows, begin + kBlock));
}

}  // namespace clutterseg
