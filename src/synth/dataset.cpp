#include "clutterseg/synth/dataset.hpp"

#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "clutterseg/debug.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/parallel.hpp"
#include "png.hpp"

namespace clutterseg::synth {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// PNG bytes with fast deflate (png.hpp): the same image always gives the same bytes.
void write_png_fast(const fs::path& path, const cv::Mat& image) {
  write_text_atomic(path, encode_png(image));
}

json vec(const Eigen::Vector3d& v) {
  // Rounded to 1e-6 (micrometres, micro-degrees) so that the text is short and stable.
  auto r = [](double x) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.6f", x);
    return std::strtod(buf, nullptr) + 0.0;  // + 0.0 turns -0 into 0
  };
  return json::array({r(v.x()), r(v.y()), r(v.z())});
}

// Extrinsic rotations about world x, then y, then z [deg]: R = Rz(c) * Ry(b) * Rx(a).
Eigen::Vector3d rotation_xyz_deg(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d zyx = R.eulerAngles(2, 1, 0);
  return Eigen::Vector3d(zyx[2], zyx[1], zyx[0]) * 180.0 / M_PI;
}

json frame_json(const std::string& name, const SynthFrame& f) {
  json objects = json::array();
  int max_id = 0;  // ids may skip removed objects (pick-and-place)
  for (const auto& o : f.scene.objects) max_id = std::max(max_id, o.id);
  std::vector<int> pixels(static_cast<size_t>(max_id) + 1, 0);
  for (int i = 0; i < f.sensor.labels.rows * f.sensor.labels.cols; ++i) {
    const int id = f.sensor.labels.at<int>(i);
    if (id > 0 && id < static_cast<int>(pixels.size())) ++pixels[static_cast<size_t>(id)];
  }
  for (const auto& o : f.scene.objects) {
    const Shape& s = f.scene.scene.shapes[static_cast<size_t>(o.shape)];
    json j = {{"id", o.id}, {"type", o.type}, {"size", vec(o.size)},
              {"pose", {{"position", vec(o.pose.translation())}, {"rotation_xyz_deg", vec(rotation_xyz_deg(o.pose.linear()))}}},
              {"visible_pixels", pixels[static_cast<size_t>(o.id)]}};
    if (s.type == ShapeType::Cup || s.type == ShapeType::Bowl) j["wall"] = vec(Eigen::Vector3d::Constant(s.wall))[0];
    if (o.held) j["held"] = true;
    objects.push_back(j);
  }
  return {{"name", name}, {"family", f.scene.family},
          {"camera", {{"position", vec(f.scene.eye)}, {"target", vec(f.scene.target)}}},
          {"objects", objects}};
}

std::string camera_json(const Camera& c, Sensor sensor) {
  json j = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"width", c.width}, {"height", c.height},
            {"depth_unit_m", 0.001}, {"sensor", to_string(sensor)}, {"source", "clutterseg synth (ray-cast scenes, exact labels)"}};
  return j.dump(1) + "\n";
}

bool is_frame_png(const fs::path& p) {
  const std::string stem = p.stem().string();
  return p.extension() == ".png" && stem.size() == 6 && std::all_of(stem.begin(), stem.end(), ::isdigit);
}

}  // namespace

std::string frame_name(int frame) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%06d", frame);
  return buf;
}

cv::Mat preview_image(const SensorFrame& frame, int width) {
  cv::Mat image = render_depth(frame.depth);
  cv::Mat ids, grow, shrink;
  frame.labels.convertTo(ids, CV_32F);  // morphology has no 32-bit integer version
  cv::dilate(ids, grow, cv::Mat());
  cv::erode(ids, shrink, cv::Mat());
  image.setTo(cv::Scalar(255, 255, 255), (grow != shrink) & (frame.labels > 0));
  const int height = std::max(1, frame.depth.rows * width / std::max(1, frame.depth.cols));
  cv::Mat small;
  cv::resize(image, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  return small;
}

SynthFrame synthesize(const std::string& preset, std::uint64_t seed, int frame, const Camera& camera, Sensor sensor) {
  SynthFrame f;
  f.scene = generate_scene(preset, seed, frame, camera);
  f.sensor = simulate(f.scene.scene, camera, f.scene.world_to_camera, sensor_model(sensor, camera.width),
                      mix_seed(seed, 0x5e7501ULL + static_cast<std::uint64_t>(frame)));
  return f;
}

void write_dataset(const DatasetOptions& o, const std::function<void(const std::string&)>& on_frame) {
  preset_info(o.preset);  // fails early on an unknown preset
  if (o.frames < 1) throw Error("--frames " + std::to_string(o.frames) + ": must be at least 1");
  if (o.frames > 999999) throw Error("--frames " + std::to_string(o.frames) + ": at most 999999 (six-digit names)");
  if (o.camera.width < 16 || o.camera.height < 16 || o.camera.width > 8192 || o.camera.height > 8192)
    throw Error("image size " + std::to_string(o.camera.width) + "x" + std::to_string(o.camera.height) + ": must be 16..8192 pixels each way");
  if (!(o.camera.fx > 0 && o.camera.fy > 0)) throw Error("camera: fx and fy must be positive");
  if (fs::exists(o.out) && !fs::is_directory(o.out)) throw Error(o.out.string() + ": exists and is not a folder");
  if (fs::exists(o.out) && !fs::is_empty(o.out)) {
    if (!o.overwrite) throw Error(o.out.string() + ": folder is not empty (give --overwrite to replace a dataset in it)");
    // Frames of an earlier, longer run would otherwise stay behind and be read as part of this one.
    for (const char* sub : {"depth", "label", "color"})
      if (fs::is_directory(o.out / sub))
        for (const auto& e : fs::directory_iterator(o.out / sub))
          if (is_frame_png(e.path()) && std::stoi(e.path().stem().string()) >= o.frames) fs::remove(e.path());
  }
  fs::create_directories(o.out);
  write_text_atomic(o.out / "camera.json", camera_json(o.camera, o.sensor));

  std::vector<json> frames(static_cast<size_t>(o.frames));
  const int preview_count = o.preview.empty() ? 0 : std::min(o.frames, 2);
  std::vector<cv::Mat> previews(static_cast<size_t>(preview_count));
  std::mutex mutex;
  std::string first_error;
  if (o.threads > 0) set_threads(o.threads);
  // One frame per task: each frame's random numbers depend only on (seed, frame), never on the thread.
#pragma omp parallel for schedule(dynamic, 1)
  for (int i = 0; i < o.frames; ++i) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (!first_error.empty()) continue;
    }
    try {
      const std::string name = frame_name(i);
      const SynthFrame f = synthesize(o.preset, o.seed, i, o.camera, o.sensor);
      write_png_fast(o.out / "depth" / (name + ".png"), f.sensor.depth_mm);
      write_png_fast(o.out / "label" / (name + ".png"), labels_to_u16(f.sensor.labels));
      write_png_fast(o.out / "color" / (name + ".png"), f.sensor.color);
      frames[static_cast<size_t>(i)] = frame_json(name, f);
      if (i < preview_count) previews[static_cast<size_t>(i)] = preview_image(f.sensor, 160);
      std::lock_guard<std::mutex> lock(mutex);
      if (on_frame) on_frame(name);
    } catch (const std::exception& e) {
      std::lock_guard<std::mutex> lock(mutex);
      if (first_error.empty()) first_error = e.what();
    }
  }
  if (o.threads > 0) set_threads(0);
  if (!first_error.empty()) throw Error(first_error);
  const json scenes = {{"preset", o.preset}, {"sensor", to_string(o.sensor)}, {"seed", o.seed},
                       {"width", o.camera.width}, {"height", o.camera.height}, {"frames", frames}};
  write_text_atomic(o.out / "scenes.json", scenes.dump(1) + "\n");
  if (preview_count > 0) {
    // Two frames per row.
    std::vector<cv::Mat> rows;
    for (int i = 0; i < preview_count; i += 2) {
      cv::Mat row = previews[static_cast<size_t>(i)];
      if (i + 1 < preview_count) cv::hconcat(row, previews[static_cast<size_t>(i) + 1], row);
      else if (preview_count > 1) cv::hconcat(row, cv::Mat::zeros(row.size(), row.type()), row);
      rows.push_back(row);
    }
    cv::Mat montage;
    cv::vconcat(rows, montage);
    std::vector<uchar> bytes;  // maximum compression: previews go into documentation
    if (!cv::imencode(".png", montage, bytes, {cv::IMWRITE_PNG_COMPRESSION, 9})) throw Error(o.preview.string() + ": cannot be encoded");
    write_text_atomic(o.preview, std::string(bytes.begin(), bytes.end()));
  }
}

}  // namespace clutterseg::synth
