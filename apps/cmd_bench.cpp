// clutterseg bench DATASET [--with lccp,organized]: per-frame time of clutterseg and its PCL peers on the
// same frames in one run, and clutterseg's per-stage times (the layout of the paper's Table III).
#include <opencv2/core/utility.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <ctime>
#include <time.h>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <sstream>
#include <thread>

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include "clutterseg/io.hpp"
#include "clutterseg/parallel.hpp"
#include "clutterseg/pipeline.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "methods.hpp"

namespace clutterseg::app {

namespace {

struct BenchOptions {
  std::string dataset, with, out;
  int frames = 0;   // 0 = all
  int warmup = 1;   // frames run before timing starts
  int repeat = 0;   // passes over the frames; 0 = enough for at least 20 timed frames
  int subsample = 1;  // keep every N-th row and column (a 640x480 set as a 320x240 sensor with N = 2)
  int load = 0;       // busy processes started for the run (a loaded machine)
  bool stream = true; // also time throughput over the stream (frames per second)
  CameraOptions camera;
  ParamOptions params;
};

// One timed configuration: a method at a thread count.
struct Runner {
  std::string label;  // as shown in the table
  int threads = 1;
  Method method;
  std::vector<double> frame_ms;                         // wall time of each timed call
  std::vector<double> cpu_ms;                           // CPU time of the calling thread (1-thread runs)
  std::map<std::string, std::vector<double>> stage_ms;  // the method's own per-stage times
  std::vector<std::string> stage_order;
  int failures = 0;
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(v.size())));  // nearest rank
  return v[std::clamp<size_t>(rank, 1, v.size()) - 1];
}

std::string fmt(double ms) {
  if (std::isnan(ms)) return "-";
  std::ostringstream s;
  s << std::fixed << std::setprecision(ms < 10 ? 2 : 1) << ms;
  return s.str();
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  return "unknown CPU";
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  std::ostringstream s;
  s << std::put_time(&tm, "%Y-%m-%d %H:%M UTC");
  return s.str();
}

std::string load_average() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  if (!(in >> a >> b >> c)) return "unknown";
  return a + " " + b + " " + c;
}

std::vector<std::string> split_names(const std::string& list) {
  std::vector<std::string> names;
  std::stringstream in(list);
  for (std::string name; std::getline(in, name, ',');)
    if (!name.empty()) names.push_back(name);
  return names;
}

// Both OpenMP (clutterseg's stages) and OpenCV's own pool (median, Gaussian) follow the thread count.
void use_threads(int threads) {
  set_threads(threads);
  cv::setNumThreads(threads == 1 ? 0 : threads);  // 0 = OpenCV runs sequentially
}

// CPU time of the calling thread: on a shared machine it leaves out the time the thread waited for a core.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// --load N: N child processes that spin at normal priority for the whole run (what a robot's other
// software does to the cores), stopped by their PIDs at the end, or by the kernel if bench dies. Each
// starts its own session, as a process started from another shell does: with Linux's autogroup
// scheduling, its own group, so bench's threads together get the cores the burners leave, not a share
// per thread.
class Load {
 public:
  explicit Load(int n) {
    for (int i = 0; i < n; ++i) {
      const pid_t pid = fork();
      if (pid < 0) throw Error("bench --load: fork failed");
      if (pid == 0) {
        prctl(PR_SET_PDEATHSIG, SIGKILL);
        setsid();
        for (;;) asm volatile("" ::: "memory");  // spin; the compiler may not drop the loop
      }
      pids_.push_back(pid);
    }
  }
  ~Load() {
    for (const pid_t pid : pids_) kill(pid, SIGKILL);
    for (const pid_t pid : pids_) waitpid(pid, nullptr, 0);
  }
  Load(const Load&) = delete;
  Load& operator=(const Load&) = delete;

 private:
  std::vector<pid_t> pids_;
};

// Throughput over the stream: one configuration, frames pushed as a sensor would, results taken in order.
struct Streamer {
  std::string label;
  int threads = 1;         // Params::threads
  bool pipeline = false;   // cross-frame Pipeline, else Segmenter::segment frame after frame
  std::unique_ptr<Segmenter> segmenter;
  std::unique_ptr<Pipeline> pipe;
  std::vector<double> fps;  // one value per pass over the frames
  double cpu_s = 0, wall_s = 0;
  size_t frames_per_pass = 0, timed_frames = 0;  // frames of all timed passes

  // Frames per second of one pass: `count` frames, cycling through `frames` (wall time from the first
  // frame in to the last result out).
  void pass(const std::vector<Frame>& frames, size_t count) {
    set_threads(threads);
    const auto start = std::chrono::steady_clock::now();
    const std::clock_t cpu_start = std::clock();
    size_t ok = 0;
    auto take = [&] {
      try {
        pipe->pop();
        ++ok;
      } catch (const Error&) {
      }
    };
    for (size_t k = 0; k < count; ++k) {
      const Frame& f = frames[k % frames.size()];
      if (pipeline) {
        if (pipe->in_flight() >= pipe->capacity()) take();
        pipe->push(f.depth, f.camera);
      } else {
        try {
          segmenter->segment(f.depth, f.camera);
          ++ok;
        } catch (const Error&) {
        }
      }
    }
    while (pipeline && pipe->in_flight() > 0) take();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    cpu_s += static_cast<double>(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    wall_s += s;
    fps.push_back(static_cast<double>(ok) / s);
    frames_per_pass = count;
    timed_frames += ok;
  }
};

void run_once(Runner& r, const Frame& frame, bool timed) {
  use_threads(r.threads);
  const double cpu_start = thread_cpu_ms();
  const auto start = std::chrono::steady_clock::now();
  MethodOutput out;
  try {
    out = r.method.run(frame);
  } catch (const Error& e) {
    if (timed) ++r.failures;
    report_error(frame.path.string() + ": " + r.label + ": " + e.what());
    return;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  const double cpu = thread_cpu_ms() - cpu_start;
  if (!timed) return;
  r.frame_ms.push_back(ms);
  if (r.threads == 1) r.cpu_ms.push_back(cpu);
  for (const auto& [stage, t] : out.timings_ms) {
    if (!r.stage_ms.count(stage)) r.stage_order.push_back(stage);
    r.stage_ms[stage].push_back(t);
  }
}

std::string command_line(const BenchOptions& o) {
  std::string c = "clutterseg bench " + o.dataset;
  if (!o.with.empty()) c += " --with " + o.with;
  if (o.params.threads) c += " --threads " + std::to_string(*o.params.threads);
  if (o.frames) c += " --frames " + std::to_string(o.frames);
  if (o.warmup != 1) c += " --warmup " + std::to_string(o.warmup);
  if (o.repeat) c += " --repeat " + std::to_string(o.repeat);
  if (o.subsample > 1) c += " --subsample " + std::to_string(o.subsample);
  if (o.load > 0) c += " --load " + std::to_string(o.load);
  if (!o.stream) c += " --no-stream";
  if (!o.params.config_file.empty()) c += " --config " + o.params.config_file;
  if (!o.out.empty()) c += " --out " + o.out;
  return c;
}

std::string threads_label(int t) { return t == 0 ? std::string("0 (default)") : std::to_string(t); }

std::string report(const BenchOptions& o, const std::vector<Runner>& runners, const std::vector<Streamer>& streams,
                   const std::vector<Frame>& frames, int passes, int cores) {
  std::ostringstream md;
  const Runner& reference = runners.front();  // clutterseg at the comparison thread count
  const double ref_median = percentile(reference.frame_ms, 0.5);
  md << "### `" << command_line(o) << "`\n\n";
  md << "- date: " << utc_now() << "\n";
  md << "- machine: " << cores << " cores (nproc), " << cpu_model() << "\n";
  md << "- load: " << (o.load > 0 ? std::to_string(o.load) + " busy process(es) at normal priority, each in its own session, started by bench (--load)"
                                  : std::string("none started by bench")) << "; load average at the end: " << load_average() << "\n";
  md << "- frames: " << frames.size() << " of " << frames.front().depth.cols << "x" << frames.front().depth.rows
     << ", " << passes << " pass(es) timed after " << o.warmup << " warm-up frame(s) per method\n";
  md << "- times are wall-clock per frame (load, I/O excluded); CPU = CPU time of the calling thread, for one-thread "
        "runs only (all their work runs on that thread)\n\n";
  const double ref_cpu = percentile(reference.cpu_ms, 0.5);
  md << "| method | threads | frames | median [ms] | p95 [ms] | median / clutterseg | CPU median [ms] | CPU / clutterseg |\n";
  md << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Runner& r : runners) {
    const double median = percentile(r.frame_ms, 0.5);
    md << "| " << r.label << " | " << threads_label(r.threads) << " | " << r.frame_ms.size()
       << (r.failures ? " (" + std::to_string(r.failures) + " failed)" : std::string()) << " | " << fmt(median)
       << " | " << fmt(percentile(r.frame_ms, 0.95)) << " | ";
    md << (ref_median > 0 && !std::isnan(median) ? fmt(median / ref_median) + "x" : std::string("-")) << " | ";
    const double cpu = percentile(r.cpu_ms, 0.5);
    md << fmt(cpu) << " | " << (ref_cpu > 0 && !std::isnan(cpu) ? fmt(cpu / ref_cpu) + "x" : std::string("-")) << " |\n";
  }
  if (!streams.empty()) {
    const double one = percentile(streams.front().fps, 0.5);
    md << "\nclutterseg throughput over the stream (" << streams.front().frames_per_pass << " frames per pass, " << streams.front().fps.size()
       << " passes, configurations interleaved pass by pass; fps = frames / wall time from the first frame in to the "
          "last result out):\n\n";
    md << "| configuration | threads | median fps | min fps | ms per frame | fps / one thread | CPU s / wall s | CPU ms per frame |\n";
    md << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const Streamer& st : streams) {
      const double fps = percentile(st.fps, 0.5);
      md << "| " << st.label << " | " << threads_label(st.threads) << " | " << fmt(fps) << " | "
         << fmt(*std::min_element(st.fps.begin(), st.fps.end())) << " | " << fmt(1000.0 / fps) << " | "
         << fmt(fps / one) << "x | " << fmt(st.wall_s > 0 ? st.cpu_s / st.wall_s : NAN) << " | "
         << fmt(st.timed_frames > 0 ? 1000.0 * st.cpu_s / static_cast<double>(st.timed_frames) : NAN) << " |\n";
    }
  }
  // clutterseg per stage, single- and multi-threaded side by side.
  std::vector<const Runner*> ours;
  for (const Runner& r : runners)
    if (r.method.name == "clutterseg") ours.push_back(&r);
  md << "\nclutterseg per stage [ms] (median / p95 over the timed frames):\n\n| stage |";
  for (const Runner* r : ours) md << " threads " << threads_label(r->threads) << " median | p95 |";
  md << "\n|---|";
  for (size_t i = 0; i < ours.size(); ++i) md << "---:|---:|";
  md << "\n";
  for (const auto& stage : ours.front()->stage_order) {
    md << "| " << stage << " |";
    for (const Runner* r : ours) {
      const auto it = r->stage_ms.find(stage);
      const std::vector<double> none;
      const auto& v = it == r->stage_ms.end() ? none : it->second;
      md << " " << fmt(percentile(v, 0.5)) << " | " << fmt(percentile(v, 0.95)) << " |";
    }
    md << "\n";
  }
  // The peers' own stages, so that one sees where their time goes.
  for (const Runner& r : runners) {
    if (r.method.name == "clutterseg" || r.stage_order.empty()) continue;
    md << "\n" << r.label << " per stage [ms], " << r.threads << " thread" << (r.threads == 1 ? "" : "s")
       << ":\n\n| stage | median | p95 |\n|---|---:|---:|\n";
    for (const auto& stage : r.stage_order) {
      const auto& v = r.stage_ms.at(stage);
      md << "| " << stage << " | " << fmt(percentile(v, 0.5)) << " | " << fmt(percentile(v, 0.95)) << " |\n";
    }
  }
  return md.str();
}

int run(const BenchOptions& o) {
  Params params = o.params.resolve();
  const int threads = o.params.threads.value_or(1);  // the comparison runs on one core unless told
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  FrameSource source(o.dataset, o.camera);

  std::vector<Runner> runners;
  auto add = [&](const std::string& name, int t) {
    Params p = params;
    p.threads = t;
    Runner r;
    r.label = name;
    r.threads = t;
    r.method = make_method(name, p);
    runners.push_back(std::move(r));
  };
  add("clutterseg", threads);
  // The default (0: idle cores at each region) and, for contrast, every core forced, beside one thread.
  if (threads == 1) {
    add("clutterseg", 0);
    if (cores > 1) add("clutterseg", cores);
  } else if (threads != 1) {
    add("clutterseg", 1);
  }
  for (const auto& name : split_names(o.with)) {
    if (name == "clutterseg") continue;
    add(name, threads);
  }

  // All frames are loaded first so that disk reads are never timed.
  std::vector<Frame> frames;
  const size_t wanted = o.frames > 0 ? std::min<size_t>(o.frames, source.size()) : source.size();
  for (size_t i = 0; i < source.size() && frames.size() < wanted; ++i) {
    try {
      frames.push_back(source.load(i));
      subsample(frames.back(), o.subsample);
    } catch (const Error& e) {
      report_error(e.what());
    } catch (const std::exception& e) {  // OpenCV, out of memory: the frame is skipped all the same
      report_error(source.path(i).string() + ": " + e.what());
    }
  }
  if (frames.empty()) throw Error(o.dataset + ": no frame could be loaded");

  const Load load(o.load);
  const int passes = o.repeat > 0 ? o.repeat : std::max(1, static_cast<int>((20 + frames.size() - 1) / frames.size()));
  const int warmup = std::min<int>(std::max(o.warmup, 0), static_cast<int>(frames.size()));
  Progress progress("bench", runners.size() * (warmup + passes * frames.size()));
  // Methods are interleaved frame by frame so that all see the same load on a shared machine.
  for (int i = 0; i < warmup; ++i)
    for (Runner& r : runners) {
      run_once(r, frames[i], false);
      progress.step(r.label + " warm-up");
    }
  for (int pass = 0; pass < passes; ++pass)
    for (const Frame& frame : frames)
      for (Runner& r : runners) {
        run_once(r, frame, true);
        progress.step(r.label + " " + frame.name);
      }
  // Throughput: one thread frame after frame, against the cross-frame Pipeline (default and forced).
  std::vector<Streamer> streams;
  if (o.stream) {
    Params sp = params;
    sp.support.objects_only = true;  // as the latency runs
    auto add_stream = [&](const std::string& label, int t, bool pipeline) {
      Streamer st;
      st.label = label;
      st.threads = t;
      st.pipeline = pipeline;
      Params p = sp;
      p.threads = t;
      if (pipeline) st.pipe = std::make_unique<Pipeline>(p);
      else st.segmenter = std::make_unique<Segmenter>(p);
      streams.push_back(std::move(st));
    };
    add_stream("Segmenter, frame after frame", 1, false);
    add_stream("Segmenter, frame after frame", 0, false);
    add_stream("Pipeline (frames across cores)", 0, true);
    if (cores > 1) add_stream("Pipeline (frames across cores)", cores, true);
    // Passes of at least 30 frames (the frames cycled), so that filling and draining the pipeline is a
    // small part of a pass; as many passes as the latency runs have.
    const size_t per_pass = frames.size() * ((30 + frames.size() - 1) / frames.size());
    const int stream_passes = std::max(3, passes);
    Progress sprog("stream", streams.size() * (stream_passes + 1));
    for (Streamer& st : streams) {  // a warm-up pass each, untimed
      st.pass(frames, frames.size());
      st.fps.clear();
      st.cpu_s = st.wall_s = 0;
      st.timed_frames = 0;
      sprog.step(st.label + " warm-up");
    }
    for (int pass = 0; pass < stream_passes; ++pass)
      for (Streamer& st : streams) {
        st.pass(frames, per_pass);
        sprog.step(st.label);
      }
  }
  use_threads(params.threads);

  const std::string md = report(o, runners, streams, frames, passes, cores);
  std::cout << md;
  if (!o.out.empty()) write_text_atomic(o.out, md);
  for (const Runner& r : runners)
    if (r.failures) return 1;
  return 0;
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto opts = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand("bench", "time clutterseg and the PCL baselines on the same frames");
  cmd->add_option("DATASET", opts->dataset, "dataset folder (camera.json + depth/), folder of PCDs, or one file")->required();
  std::string names;
  for (const auto& n : available_methods())
    if (n != "clutterseg") names += (names.empty() ? "" : ",") + n;
  cmd->add_option("--with", opts->with, "comma-separated peers to time beside clutterseg (this build: " +
                                            (names.empty() ? std::string("none") : names) + ")");
  cmd->add_option("--frames", opts->frames, "use only the first N frames (default all)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--warmup", opts->warmup, "untimed frames per method before timing (default 1)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--repeat", opts->repeat, "timed passes over the frames (default: enough for >= 20 timed frames)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--subsample", opts->subsample, "keep every N-th row and column, intrinsics scaled (2: a 640x480 set as 320x240)")
      ->check(CLI::Range(1, 16));
  cmd->add_option("--load", opts->load, "start N busy processes for the run: times on a loaded machine (default 0)")
      ->check(CLI::Range(0, 64));
  cmd->add_flag("!--no-stream", opts->stream, "skip the throughput runs (frames per second over the stream)");
  cmd->add_option("--out", opts->out, "also write the markdown tables to this file");
  opts->camera.add_to(*cmd);
  opts->params.add_to(*cmd);  // --threads N: the comparison's thread count (bench default 1)
  cmd->callback([opts] { throw CLI::RuntimeError(run(*opts)); });
}

}  // namespace clutterseg::app
