#include "common.hpp"

#include <cstring>
#include <unistd.h>

#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "clutterseg/config.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/limits.hpp"
#ifdef CLUTTERSEG_WITH_PCL
#include "clutterseg/pcl/pcd.hpp"
#endif

namespace clutterseg::app {

void CameraOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--camera", file, "intrinsics JSON {fx, fy, cx, cy, width, height, depth_unit_m}")->check(CLI::ExistingFile);
  cmd.add_option("--fx", fx, "focal length x [px]");
  cmd.add_option("--fy", fy, "focal length y [px]");
  cmd.add_option("--cx", cx, "principal point x [px]");
  cmd.add_option("--cy", cy, "principal point y [px]");
  cmd.add_option("--depth-unit", depth_unit, "metres per step of 16-bit depth (default 0.001)");
}

std::optional<Camera> CameraOptions::resolve(int width, int height, const std::optional<Camera>& fallback) const {
  std::optional<Camera> cam;
  if (!file.empty()) cam = read_camera_json(file);
  else if (fallback) cam = fallback;
  if (fx || fy || cx || cy) {
    if (!cam) {
      if (!fx) return std::nullopt;
      cam = Camera{};
      cam->fx = *fx;
      cam->fy = fy.value_or(*fx);
      cam->cx = cx.value_or((width - 1) / 2.0);
      cam->cy = cy.value_or((height - 1) / 2.0);
      cam->width = width;
      cam->height = height;
    } else {
      if (fx) cam->fx = *fx;
      if (fy) cam->fy = *fy;
      if (cx) cam->cx = *cx;
      if (cy) cam->cy = *cy;
    }
  }
  if (cam && depth_unit) cam->depth_unit_m = *depth_unit;
  return cam;
}

void ParamOptions::add_to(CLI::App& cmd) {
  cmd.add_option("--config", config_file, "parameters JSON (see --dump-config)")->check(CLI::ExistingFile);
  cmd.add_option("--theta-c", theta_c, "graph-cut threshold Theta_c (paper default 0.5)");
  cmd.add_option("--theta-h", theta_h, "curvature-similarity threshold Theta_h (paper default 0.5)");
  cmd.add_option("--seed", seed, "seed for every random choice");
  cmd.add_option("--threads", threads, "row threads per frame (0 = the idle cores but one; serial on 2 cores)");
  cmd.add_flag("--no-temporal", no_temporal, "treat frames independently (no temporal smoothing)");
  cmd.add_flag("--objects-only", objects_only, "label 0 for the table and background surfaces");
  cmd.add_flag("--no-tracking", no_tracking, "number objects 1..M afresh every frame (no stable ids across frames)");
}

Params ParamOptions::resolve() const {
  Params p = config_file.empty() ? Params{} : read_params_file(config_file);
  if (theta_c) p.graph.theta_c = *theta_c;
  if (theta_h) p.curvature.theta_h = *theta_h;
  if (seed) p.seed = *seed;
  if (threads) p.threads = *threads;
  if (no_temporal) p.smoothing.temporal = false;
  if (objects_only) p.support.objects_only = true;
  if (no_tracking) p.tracking.enabled = false;
  validate(p);  // the flags' values too (the config file's were checked when it was read)
  return p;
}

FrameSource::FrameSource(const fs::path& input, const CameraOptions& camera) : camera_(camera) {
  if (!fs::exists(input)) throw Error(input.string() + ": no such file or folder");
  if (fs::is_directory(input)) {
    if (fs::is_directory(input / "depth")) {
      for (const auto& f : list_dataset(input)) entries_.push_back({f.name, f.depth, f.color, f.label});
      if (fs::exists(input / "camera.json")) dataset_camera_ = read_camera_json(input / "camera.json");
    } else {
      for (const auto& e : fs::directory_iterator(input))
        if (e.path().extension() == ".pcd" || e.path().extension() == ".png")
          entries_.push_back({e.path().stem().string(), e.path(), {}, {}});
      std::sort(entries_.begin(), entries_.end(), [](const auto& a, const auto& b) { return a.name < b.name; });
      if (entries_.empty()) throw Error(input.string() + ": folder holds no depth/ subfolder, .png or .pcd files");
      if (fs::exists(input / "camera.json")) dataset_camera_ = read_camera_json(input / "camera.json");
    }
  } else {
    Entry e{input.stem().string(), input, {}, {}};
    // A PNG inside <set>/depth/ finds its colour image and the set's camera.json.
    const fs::path set = input.parent_path().parent_path();
    if (input.parent_path().filename() == "depth") {
      if (auto c = set / "color" / input.filename(); fs::exists(c)) e.color = c;
      if (auto l = set / "label" / input.filename(); fs::exists(l)) e.label = l;
      if (fs::exists(set / "camera.json")) dataset_camera_ = read_camera_json(set / "camera.json");
    }
    entries_.push_back(e);
  }
}

Frame FrameSource::load(size_t i) const {
  const Entry& e = entries_.at(i);
  Frame f;
  f.name = e.name;
  f.path = e.depth;
  if (e.depth.extension() == ".pcd") {
#ifdef CLUTTERSEG_WITH_PCL
    PcdFrame pcd = read_organized_pcd(e.depth, {});
    // Explicit intrinsics win over the ones recovered from the cloud, but must fit it.
    if (auto given = camera_.resolve(pcd.depth.cols, pcd.depth.rows, dataset_camera_)) {
      check_camera(*given, pcd.depth.cols, pcd.depth.rows, e.depth.string());
      pcd.camera = *given;
    }
    f.depth = pcd.depth;
    f.color = pcd.color;
    f.camera = pcd.camera;
    return f;
#else
    throw Error(e.depth.string() + ": PCD input needs clutterseg built with PCL");
#endif
  }
  f.depth = read_depth_png(e.depth);
  auto cam = camera_.resolve(f.depth.cols, f.depth.rows, dataset_camera_);
  if (!cam) throw Error(e.depth.string() + ": no intrinsics; give --camera FILE.json or --fx/--fy/--cx/--cy");
  check_camera(*cam, f.depth.cols, f.depth.rows, e.depth.string());
  f.camera = *cam;
  if (e.color) {
    try {
      f.color = read_png(*e.color, cv::IMREAD_COLOR);
    } catch (const Error&) {
      f.color.release();  // a colour image is only decoration: one that cannot be read is left out
    }
    if (f.color.size() != f.depth.size()) f.color.release();  // a colour image of another size is only decoration
  }
  if (e.label) {
    f.label = read_label_png(*e.label);
    if (f.label.size() != f.depth.size())
      throw Error(e.label->string() + ": label image size differs from the depth image");
  }
  return f;
}

void subsample(Frame& frame, int n) {
  if (n <= 1) return;
  const auto every_nth = [n](const cv::Mat& image) {
    if (image.empty()) return image;
    cv::Mat out(image.rows / n, image.cols / n, image.type());
    for (int y = 0; y < out.rows; ++y)
      for (int x = 0; x < out.cols; ++x) std::memcpy(out.ptr(y, x), image.ptr(y * n, x * n), image.elemSize());
    return out;
  };
  frame.depth = every_nth(frame.depth);
  frame.color = every_nth(frame.color);
  frame.label = every_nth(frame.label);
  Camera& c = frame.camera;
  c.fx /= n;
  c.fy /= n;
  c.cx /= n;
  c.cy /= n;
  c.width = frame.depth.cols;
  c.height = frame.depth.rows;
}

Progress::Progress(std::string what, size_t total)
    : what_(std::move(what)), total_(total), enabled_(isatty(STDERR_FILENO) && total > 1) {}

void Progress::step(const std::string& item) {
  ++done_;
  if (!enabled_) return;
  constexpr int kWidth = 30;
  const int filled = static_cast<int>(kWidth * done_ / std::max<size_t>(total_, 1));
  std::cerr << "\r" << what_ << " [" << std::string(filled, '#') << std::string(kWidth - filled, ' ') << "] "
            << done_ << "/" << total_ << " " << item.substr(0, 30) << "\033[K" << std::flush;
}

Progress::~Progress() {
  if (enabled_) std::cerr << "\n";
}

void report_error(const std::string& message) { std::cerr << "clutterseg: " << message << "\n"; }

// Families and scenes from DATASET/scenes.json {"frames": [{"name", "family", "scene"?}, ...]}.
// Without a scene entry every frame is its own scene, or all frames one scene with --sequence.
std::map<std::string, FrameInfo> frame_infos(const fs::path& dataset, const FrameSource& source, bool sequence) {
  std::map<std::string, FrameInfo> infos;
  for (size_t i = 0; i < source.size(); ++i)
    infos[source.name(i)] = {"all", sequence ? std::string("sequence") : source.name(i)};
  const fs::path file = dataset / "scenes.json";
  if (!fs::exists(file)) return infos;
  nlohmann::json j;
  try {
    std::ifstream in(file);
    j = nlohmann::json::parse(in);
  } catch (const std::exception& e) {
    throw Error(file.string() + ": is not valid JSON");
  }
  if (!j.is_object() || !j.contains("frames") || !j["frames"].is_array())
    throw Error(file.string() + ": expected {\"frames\": [{\"name\": ..., \"family\": ...}, ...]}");
  for (auto& [name, info] : infos) info.family = "unlisted";
  for (const auto& f : j["frames"]) {
    if (!f.is_object() || !f.contains("name") || !f["name"].is_string())
      throw Error(file.string() + ": every frame needs a \"name\"");
    const auto it = infos.find(f["name"].get<std::string>());
    if (it == infos.end()) continue;  // a frame the dataset does not hold
    // A listed frame without a family is only in "all" (scenes.json may name scenes only).
    it->second.family = f.contains("family") && f["family"].is_string() ? f["family"].get<std::string>() : "all";
    if (f.contains("scene") && (f["scene"].is_string() || f["scene"].is_number()))
      it->second.scene = f["scene"].is_string() ? f["scene"].get<std::string>() : f["scene"].dump();
  }
  return infos;
}

}  // namespace clutterseg::app
