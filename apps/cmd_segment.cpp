// clutterseg segment INPUT --out DIR: labels, debug images and a JSON summary per frame.
#include <iostream>

#include "clutterseg/debug.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/objects.hpp"
#include "clutterseg/segmenter.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "result_json.hpp"

namespace clutterseg::app {

namespace {

struct SegmentOptions {
  std::string input, out;
  bool no_debug = false;
  CameraOptions camera;
  ParamOptions params;
};

// Renders every output of one frame in memory, then writes them; a failure leaves no file of the frame.
void write_frame(const fs::path& out, const Frame& frame, const Result& r, const Params& params) {
  std::vector<std::pair<fs::path, cv::Mat>> images;
  const fs::path debug = out / "debug" / frame.name;
  images.emplace_back(out / "patch" / (frame.name + ".png"), labels_to_u16(r.core_patch_labels));  // 0 = edge
  if (!r.object_labels.empty()) {
    const cv::Mat labels = params.support.objects_only ? objects_only(r.object_labels, r.objects, params.tracking.enabled)
                                                       : r.object_labels;
    images.emplace_back(out / "label" / (frame.name + ".png"), labels_to_u16(labels));
    images.emplace_back(debug / "objects.png", render_overlay(labels, frame.color, r.depth));
    images.emplace_back(debug / "graph.png", render_graph(r, frame.camera));
  }
  images.emplace_back(debug / "depth.png", render_depth(r.depth));
  images.emplace_back(debug / "normals.png", render_normals(r.normals));
  images.emplace_back(debug / "edges.png", render_edges(r.edges));
  images.emplace_back(debug / "edge_value.png", render_edge_value(r.edge_value));
  images.emplace_back(debug / "patches.png", render_labels(r.core_patch_labels));
  const std::string json = result_to_json(r, frame.name).dump(1) + "\n";

  std::vector<fs::path> written;
  try {
    for (const auto& [path, image] : images) {
      write_png_atomic(path, image);
      written.push_back(path);
    }
    write_text_atomic(out / (frame.name + ".json"), json);
  } catch (...) {
    std::error_code ec;
    for (const auto& path : written) fs::remove(path, ec);
    throw;
  }
}

int run(const SegmentOptions& o) {
  const Params params = o.params.resolve();
  FrameSource source(o.input, o.camera);
  Segmenter segmenter(params);
  // A dataset's scenes.json says where one scene ends and the next begins: the temporal window never
  // spans two scenes. Without it the frames are one stream and the smoother detects cuts itself.
  const fs::path folder = fs::is_directory(o.input) ? fs::path(o.input) : fs::path(o.input).parent_path();
  const auto infos = frame_infos(folder, source, /*sequence=*/true);
  std::string scene = source.size() > 0 ? infos.at(source.name(0)).scene : "";
  Progress progress("segment", source.size());
  int failed = 0;
  for (size_t i = 0; i < source.size(); ++i) {
    try {
      if (const std::string& s = infos.at(source.name(i)).scene; s != scene) {
        segmenter.reset();
        scene = s;
      }
      const Frame frame = source.load(i);
      Result r;
      try {
        r = segmenter.segment(frame.depth, frame.camera);
      } catch (const Error& e) {
        throw Error(frame.path.string() + ": " + e.what());
      }
      write_frame(o.out, frame, r, params);
    } catch (const Error& e) {
      // A bad frame is reported and skipped; it never entered the temporal window.
      report_error(e.what());
      ++failed;
    } catch (const std::exception& e) {
      // Not the project's own error (OpenCV, out of memory, the file system): still one frame's problem.
      report_error(source.path(i).string() + ": " + e.what());
      ++failed;
    }
    progress.step(source.name(i));
  }
  return failed == 0 ? 0 : 1;
}

}  // namespace

void add_segment_command(CLI::App& app) {
  auto opts = std::make_shared<SegmentOptions>();
  CLI::App* cmd = app.add_subcommand("segment", "segment depth frames into patches and objects");
  cmd->add_option("INPUT", opts->input, "depth PNG, organized PCD, dataset folder or folder of PCDs")->required();
  cmd->add_option("--out", opts->out, "output folder")->required();
  opts->camera.add_to(*cmd);
  opts->params.add_to(*cmd);
  cmd->callback([opts] { throw CLI::RuntimeError(run(*opts)); });
}

}  // namespace clutterseg::app
