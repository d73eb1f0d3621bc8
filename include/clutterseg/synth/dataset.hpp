// A synthetic dataset in the layout of SPEC Sec. 3, written by `clutterseg synth`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "clutterseg/synth/generator.hpp"
#include "clutterseg/synth/sensor.hpp"

namespace clutterseg::synth {

// One frame: the scene description and what the sensor reports.
struct SynthFrame {
  GeneratedScene scene;
  SensorFrame sensor;
};

// Frame `frame` of `preset`; a function of its arguments only (noise seeded from seed and frame).
SynthFrame synthesize(const std::string& preset, std::uint64_t seed, int frame, const Camera& camera, Sensor sensor);

struct DatasetOptions {
  std::string preset;
  int frames = 10;
  std::uint64_t seed = 0;
  std::filesystem::path out;
  Camera camera = default_camera();
  Sensor sensor = Sensor::KinectV1;
  int threads = 0;          // 0 = all cores; the bytes written do not depend on it
  bool overwrite = false;   // write into a non-empty folder (replacing earlier frames)
  std::filesystem::path preview;  // optional: the first two frames side by side, 160x120 each
};

// What a person looks at: the reported depth colour-mapped (black = no measurement) with every
// object's exact outline in white, scaled to `width` pixels.
cv::Mat preview_image(const SensorFrame& frame, int width = 320);

// Frame names: six-digit frame numbers ("000000", ...).
std::string frame_name(int frame);

// Writes DIR/camera.json, depth/, label/, color/ (one PNG each per frame) and DIR/scenes.json (written
// last). Frames are rendered in parallel; `on_frame` is called once per finished frame, one call at a
// time. Throws Error for bad options or a failed write; every file is written atomically.
void write_dataset(const DatasetOptions& options, const std::function<void(const std::string&)>& on_frame = {});

}  // namespace clutterseg::synth
