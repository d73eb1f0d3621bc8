// What the subcommands share: finding and loading input frames, camera options, the progress bar.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "clutterseg/params.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg::app {

namespace fs = std::filesystem;

// Intrinsics from --camera FILE.json or from --fx/--fy/--cx/--cy (flags override the file).
struct CameraOptions {
  std::string file;
  std::optional<double> fx, fy, cx, cy, depth_unit;
  void add_to(CLI::App& cmd);
  // Intrinsics for an image of width x height; `fallback` (e.g. the dataset's camera.json) is used
  // when no option was given. Returns nullopt when nothing at all is known.
  std::optional<Camera> resolve(int width, int height, const std::optional<Camera>& fallback) const;
};

// Parameters: --config FILE.json, then the flags every subcommand shares.
struct ParamOptions {
  std::string config_file;
  std::optional<double> theta_c, theta_h;
  std::optional<std::uint64_t> seed;
  std::optional<int> threads;
  bool no_temporal = false, objects_only = false, no_tracking = false;
  void add_to(CLI::App& cmd);
  Params resolve() const;
};

struct Frame {
  std::string name;
  fs::path path;     // the depth file
  cv::Mat depth;     // CV_16U or CV_32F metres
  cv::Mat color;     // BGR or empty
  cv::Mat label;     // CV_32S ground truth or empty
  Camera camera;
};

// Every n-th row and column of the frame (depth, colour and labels, nearest neighbour: no new values), with
// the intrinsics scaled to match: the scene as a sensor with n times fewer pixels per axis sees it.
void subsample(Frame& frame, int n);

// INPUT may be a depth PNG, an organized PCD, a dataset folder (SPEC Sec. 3) or a folder of PCDs.
class FrameSource {
 public:
  FrameSource(const fs::path& input, const CameraOptions& camera);
  size_t size() const { return entries_.size(); }
  const std::string& name(size_t i) const { return entries_[i].name; }
  const fs::path& path(size_t i) const { return entries_[i].depth; }
  // Loads frame i; throws Error naming the file on any problem.
  Frame load(size_t i) const;

 private:
  struct Entry {
    std::string name;
    fs::path depth;
    std::optional<fs::path> color, label;
  };
  std::vector<Entry> entries_;
  std::optional<Camera> dataset_camera_;
  CameraOptions camera_;
};

// A frame's family and scene from DATASET/scenes.json {"frames": [{"name", "family", "scene"?}, ...]}.
struct FrameInfo {
  std::string family = "all", scene;
};
// Without a scene entry every frame is its own scene, or all frames one scene with `sequence`.
std::map<std::string, FrameInfo> frame_infos(const fs::path& dataset, const FrameSource& source, bool sequence);

// A one-line progress bar on stderr, shown only when stderr is a terminal.
class Progress {
 public:
  Progress(std::string what, size_t total);
  void step(const std::string& item);
  ~Progress();

 private:
  std::string what_;
  size_t total_, done_ = 0;
  bool enabled_;
};

// Prints "clutterseg: <message>" to stderr.
void report_error(const std::string& message);

}  // namespace clutterseg::app
