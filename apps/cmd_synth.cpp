// clutterseg synth --preset NAME --frames N --seed S --out DIR: synthetic scenes with exact labels.
#include <iostream>
#include <regex>

#include "clutterseg/io.hpp"
#include "clutterseg/synth/dataset.hpp"
#include "commands.hpp"
#include "common.hpp"

namespace clutterseg::app {

namespace {

struct SynthOptions {
  std::string preset, out, size = "640x480", sensor = "kinect-v1", camera_file, preview;
  int frames = 10, threads = 0;
  std::uint64_t seed = 0;
  bool list = false, overwrite = false;
};

Camera resolve_camera(const SynthOptions& o, bool size_given) {
  if (!o.camera_file.empty()) {
    Camera c = read_camera_json(o.camera_file);
    if (size_given && o.size != std::to_string(c.width) + "x" + std::to_string(c.height))
      throw Error("--size " + o.size + ": differs from " + o.camera_file + " (" + std::to_string(c.width) + "x" +
                  std::to_string(c.height) + "); give one of them");
    return c;
  }
  static const std::regex pattern(R"((\d{1,5})x(\d{1,5}))");
  std::smatch m;
  if (!std::regex_match(o.size, m, pattern)) throw Error("--size " + o.size + ": expected WIDTHxHEIGHT, e.g. 640x480");
  return synth::default_camera(std::stoi(m[1]), std::stoi(m[2]));
}

int run(const SynthOptions& o, bool size_given) {
  if (o.list) {
    for (const auto& p : synth::presets())
      std::cout << p.name << std::string(p.name.size() < 26 ? 26 - p.name.size() : 1, ' ') << p.description << "\n";
    return 0;
  }
  if (o.preset.empty()) throw Error("--preset is required (see --list)");
  if (o.out.empty()) throw Error("--out is required");
  synth::DatasetOptions d;
  d.preset = o.preset;
  d.frames = o.frames;
  d.seed = o.seed;
  d.out = o.out;
  d.sensor = synth::parse_sensor(o.sensor);
  d.camera = resolve_camera(o, size_given);
  d.threads = o.threads;
  d.overwrite = o.overwrite;
  d.preview = o.preview;
  synth::preset_info(d.preset);
  // Frames are rendered in parallel already; OpenCV's own thread pool inside each frame only adds overhead.
  cv::setNumThreads(1);
  Progress progress("synth", static_cast<size_t>(std::max(o.frames, 0)));
  synth::write_dataset(d, [&](const std::string& name) { progress.step(name); });
  return 0;
}

}  // namespace

void add_synth_command(CLI::App& app) {
  auto o = std::make_shared<SynthOptions>();
  CLI::App* cmd = app.add_subcommand("synth", "write a synthetic dataset with exact labels and a depth-sensor model");
  cmd->add_option("--preset", o->preset, "scene preset or family (see --list)");
  auto* size = cmd->add_option("--size", o->size, "image size WIDTHxHEIGHT (default 640x480; fx = 525 * width / 640)");
  cmd->add_option("--frames", o->frames, "number of frames (default 10)");
  cmd->add_option("--seed", o->seed, "seed: the same seed gives the same bytes (default 0)");
  cmd->add_option("--out", o->out, "output folder (camera.json, depth/, label/, color/, scenes.json)");
  cmd->add_option("--sensor", o->sensor, "kinect-v1 (default), realsense-d435 or ideal");
  cmd->add_option("--camera", o->camera_file, "intrinsics JSON {fx, fy, cx, cy, width, height}")->check(CLI::ExistingFile);
  cmd->add_option("--threads", o->threads, "threads (0 = all cores); the output does not depend on it");
  cmd->add_option("--preview", o->preview, "also write a PNG of the first two frames (depth colour-mapped, objects outlined)");
  cmd->add_flag("--overwrite", o->overwrite, "write into a non-empty folder, replacing an earlier dataset");
  cmd->add_flag("--list", o->list, "print the presets and exit");
  cmd->callback([o, size] {
    const int code = run(*o, size->count() > 0);
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace clutterseg::app
