// clutterseg eval DATASET [--pred DIR] [--out DIR]: both metric families of SPEC Sec. 4 over a labelled
// dataset, per family, optionally over a parameter sweep; tables on stdout, CSV/JSON/HTML in --out.
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>

#include "clutterseg/config.hpp"
#include "clutterseg/debug.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/metrics.hpp"
#include "commands.hpp"
#include "common.hpp"
#include "methods.hpp"
#include "report.hpp"

namespace clutterseg::app {

namespace {

struct EvalOptions {
  std::string dataset, pred, out, sweep;
  std::vector<std::string> with;
  bool sequence = false;
  int report_frames = 24;
  int subsample = 1;  // keep every N-th row and column (a 640x480 set scored as a 320x240 sensor with N = 2)
  CameraOptions camera;
  ParamOptions params;
};

// --sweep NAME=START:STOP:STEP over one numeric parameter (theta_c, theta_h or a dotted JSON path).
struct Sweep {
  std::string name;  // as typed
  std::string path;  // in the parameters JSON, e.g. "graph.theta_c"
  std::vector<double> values;
};

Sweep parse_sweep(const std::string& text) {
  const auto fail = [&](const std::string& why) {
    return Error("--sweep " + text + ": " + why + " (expected NAME=START:STOP:STEP, e.g. theta_c=0.3:0.9:0.1)");
  };
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) throw fail("no NAME=");
  Sweep s;
  s.name = text.substr(0, eq);
  s.path = s.name == "theta_c" ? "graph.theta_c" : s.name == "theta_h" ? "curvature.theta_h" : s.name;
  double start = 0, stop = 0, step = 0;
  char c1 = 0, c2 = 0;
  std::istringstream in(text.substr(eq + 1));
  if (!(in >> start >> c1 >> stop >> c2 >> step) || c1 != ':' || c2 != ':' || !(in >> std::ws).eof())
    throw fail("the range is not START:STOP:STEP");
  if (!(step > 0) || stop < start) throw fail("needs STEP > 0 and STOP >= START");
  const double count = std::floor((stop - start) / step + 1e-9) + 1;
  if (count > 200) throw fail("more than 200 values");
  for (int k = 0; k < static_cast<int>(count); ++k)
    s.values.push_back(std::round((start + k * step) * 1e9) / 1e9);  // 0.3 + 2 * 0.1 prints as 0.5
  return s;
}

// `base` with the parameter at the dotted `path` set to `value`; Error for unknown or non-numeric paths.
Params with_value(const Params& base, const Sweep& sweep, double value) {
  nlohmann::json j = nlohmann::json::parse(params_to_json(base));
  nlohmann::json* node = &j;
  std::istringstream keys(sweep.path);
  std::string key;
  while (std::getline(keys, key, '.')) {
    if (!node->is_object() || !node->contains(key))
      throw Error("--sweep: unknown parameter '" + sweep.name + "' (theta_c, theta_h or a path of --dump-config)");
    node = &(*node)[key];
  }
  if (node->is_number_integer()) {
    if (value != std::round(value)) throw Error("--sweep: '" + sweep.name + "' takes whole numbers");
    *node = static_cast<long long>(std::llround(value));
  } else if (node->is_number_float()) {
    *node = value;
  } else {
    throw Error("--sweep: '" + sweep.name + "' is not a numeric parameter");
  }
  return params_from_json(j.dump(), "--sweep");
}

cv::Mat depth_in_metres(const Frame& frame) {
  cv::Mat m;
  if (frame.depth.depth() == CV_16U) {
    frame.depth.convertTo(m, CV_32F, frame.camera.depth_unit_m);
  } else {
    m = frame.depth.clone();
    cv::patchNaNs(m, 0);
  }
  return m;
}

// A small JPEG for the report: photos and label overlays compress well enough to keep the page light.
std::string thumbnail(const cv::Mat& bgr) {
  constexpr int kWidth = 300;
  cv::Mat small;
  if (bgr.cols > kWidth)
    cv::resize(bgr, small, cv::Size(kWidth, std::max(1, bgr.rows * kWidth / bgr.cols)), 0, 0, cv::INTER_AREA);
  else
    small = bgr;
  std::vector<uchar> buf;
  cv::imencode(".jpg", small, buf, {cv::IMWRITE_JPEG_QUALITY, 85});
  return std::string(buf.begin(), buf.end());
}

// Predicted labels from another tool: DIR/NAME.png, or DIR/label/NAME.png as `segment --out DIR` writes.
Method prediction_folder(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw Error(dir.string() + ": --pred needs a folder of label PNGs");
  return {"pred", [dir](const Frame& frame) {
            fs::path file = dir / (frame.name + ".png");
            if (!fs::exists(file) && fs::exists(dir / "label" / (frame.name + ".png")))
              file = dir / "label" / (frame.name + ".png");
            if (!fs::exists(file)) throw Error(file.string() + ": no prediction for frame " + frame.name);
            return MethodOutput{read_label_png(file), {}};
          }};
}

struct Evaluation {
  const FrameSource& source;
  const std::map<std::string, FrameInfo>& infos;
  fs::path dataset;
  int gallery_frames = 0;
  int subsample = 1;
};

// Makes a fresh method: one per scene, so no temporal state leaks from one scene into the next.
using MethodFactory = std::function<Method()>;

// Runs one method over every frame in order; a frame that fails is recorded and the run goes on.
void run_over_frames(const Evaluation& ev, const MethodFactory& make, RunRecord& run, EvalReport& report) {
  Method method = make();
  std::string scene = ev.source.size() > 0 ? ev.infos.at(ev.source.name(0)).scene : "";
  TrackingScorer tracking;  // per scene
  const bool fill_gallery = report.gallery.empty();
  std::vector<std::pair<std::string, std::pair<double, int>>> stage_sums;
  Progress progress("eval " + run.label, ev.source.size());
  for (size_t i = 0; i < ev.source.size(); ++i) {
    const std::string& name = ev.source.name(i);
    FrameRecord rec;
    rec.frame = name;
    rec.family = ev.infos.at(name).family;
    rec.scene = ev.infos.at(name).scene;
    if (rec.scene != scene) {
      method = make();
      scene = rec.scene;
      run.tracking += tracking.scores();
      tracking = TrackingScorer();
    }
    try {
      Frame frame = ev.source.load(i);
      subsample(frame, ev.subsample);
      if (frame.label.empty())
        throw Error((ev.dataset / "label" / (name + ".png")).string() + ": no ground truth for this frame");
      MethodOutput out;
      try {
        out = method.run(frame);
      } catch (const Error& e) {
        if (method.name == "pred") throw;  // the message already names the prediction file
        throw Error(frame.path.string() + ": " + e.what());
      }
      rec.scores = score_frame(frame.label, out.labels);
      // The depth tells which lost pixels no depth-only method could place (a --pred run scores labels of
      // any size: the figure is left out where the depth does not fit them).
      rec.errors = error_breakdown(frame.label, out.labels, rec.scores.matches,
                                   frame.depth.size() == frame.label.size() ? frame.depth : cv::Mat());
      tracking.add(frame.label, out.labels);
      report.boundary_tolerance_px = boundary_tolerance_px(frame.label.size());  // one camera per set
      for (const auto& [stage, ms] : out.timings_ms) {
        auto it = std::find_if(stage_sums.begin(), stage_sums.end(),
                               [&stage = stage](const auto& s) { return s.first == stage; });  // clang 14 (sanitizers)
        if (it == stage_sums.end()) it = stage_sums.insert(stage_sums.end(), {stage, {0.0, 0}});
        it->second.first += ms;
        ++it->second.second;
        if (stage == "total") rec.total_ms = ms;
      }
      if (static_cast<int>(i) < ev.gallery_frames) {
        try {
          const cv::Mat depth_m = depth_in_metres(frame);
          run.predictions.emplace_back(name, thumbnail(render_overlay(out.labels, frame.color, depth_m)));
          if (fill_gallery) {
            const cv::Mat image = frame.color.empty() ? render_depth(depth_m) : frame.color;
            report.gallery.push_back(
                {name, rec.family, thumbnail(image), thumbnail(render_overlay(frame.label, frame.color, depth_m))});
          }
        } catch (const std::exception& e) {  // a picture that cannot be drawn does not cost the scores
          report_error(run.label + ": " + name + ": no picture for the report: " + e.what());
        }
      }
    } catch (const std::exception& e) {  // Error, or an OpenCV/PCL exception inside a method
      rec.error = e.what();
      report_error(run.label + ": " + rec.error);
    }
    run.frames.push_back(std::move(rec));
    progress.step(name);
  }
  run.tracking += tracking.scores();
  for (const auto& [stage, sum] : stage_sums) run.mean_timings_ms.emplace_back(stage, sum.first / sum.second);
}

std::string command_line(const EvalOptions& o) {
  std::string c = "clutterseg eval " + o.dataset;
  if (!o.pred.empty()) c += " --pred " + o.pred;
  if (!o.with.empty()) {
    c += " --with ";
    for (size_t i = 0; i < o.with.size(); ++i) c += (i ? "," : "") + o.with[i];
  }
  if (!o.sweep.empty()) c += " --sweep " + o.sweep;
  if (o.sequence) c += " --sequence";
  if (o.subsample > 1) c += " --subsample " + std::to_string(o.subsample);
  if (!o.out.empty()) c += " --out " + o.out;
  return c;
}

int run(const EvalOptions& o) {
  const Params base = o.params.resolve();
  if (!fs::is_directory(fs::path(o.dataset) / "depth"))
    throw Error(o.dataset + ": is not a dataset folder (SPEC Sec. 3: camera.json, depth/, label/)");
  if (!o.pred.empty() && (!o.with.empty() || !o.sweep.empty()))
    throw Error("--pred scores given predictions; it cannot be combined with --with or --sweep");
  if (!o.pred.empty() && o.subsample > 1)
    throw Error("--pred scores given predictions at their own size; it cannot be combined with --subsample");
  const FrameSource source(o.dataset, o.camera);
  const auto infos = frame_infos(o.dataset, source, o.sequence);
  std::optional<Sweep> sweep;
  if (!o.sweep.empty()) sweep = parse_sweep(o.sweep);

  // Every method is made before the first frame, so a bad name or parameter fails at once.
  std::vector<std::pair<RunRecord, MethodFactory>> runs;
  const auto factory = [](const std::string& name, const Params& params) {
    make_method(name, params);  // an unknown name fails here, before the first frame
    return MethodFactory([name, params] { return make_method(name, params); });
  };
  if (!o.pred.empty()) {
    RunRecord r;
    r.method = "pred";
    r.label = fs::path(o.pred).filename().string();  // the folder's name says which tool made it
    if (r.label.empty() || r.label == ".") r.label = "pred";
    const Method pred = prediction_folder(o.pred);
    runs.emplace_back(r, [pred] { return pred; });
  } else if (sweep) {
    for (double v : sweep->values) {
      RunRecord r;
      r.method = "clutterseg";
      r.setting = {{sweep->name, v}};
      std::ostringstream label;
      label << "clutterseg " << sweep->name << "=" << v;
      r.label = label.str();
      runs.emplace_back(r, factory("clutterseg", with_value(base, *sweep, v)));
    }
  } else {
    RunRecord r;
    r.method = r.label = "clutterseg";
    runs.emplace_back(r, factory("clutterseg", base));
  }
  for (const auto& name : o.with) {
    if (name == "clutterseg") continue;
    RunRecord r;
    r.method = r.label = name;
    runs.emplace_back(r, factory(name, base));
  }

  EvalReport report;
  report.dataset = o.dataset;
  report.command = command_line(o);
  report.frames = static_cast<int>(source.size());
  std::set<std::string> scenes;
  for (const auto& [name, info] : infos) scenes.insert(info.scene);
  report.scenes = static_cast<int>(scenes.size());
  if (o.pred.empty()) report.params_json = params_to_json(base);
  if (sweep) report.sweep_parameter = sweep->name;

  const Evaluation ev{source, infos, o.dataset, o.out.empty() ? 0 : std::max(0, o.report_frames), o.subsample};
  for (auto& [record, make] : runs) {
    run_over_frames(ev, make, record, report);
    record.groups = summarize(record.frames);
    report.runs.push_back(std::move(record));
  }

  // The sweep's best value by Overlap F over all frames; it is the clutterseg run shown in the plots.
  RunRecord* best = nullptr;
  for (auto& r : report.runs) {
    if (r.setting.empty()) {
      r.shown = true;
      continue;
    }
    const double f = r.all().scores[5].mean;
    if (std::isfinite(f) && (!best || f > best->all().scores[5].mean)) best = &r;
  }
  if (best) best->best = best->shown = true;
  if (sweep && !best)
    for (auto& r : report.runs) r.shown = r.shown || !r.setting.empty();

  std::cout << format_tables(report) << std::flush;
  if (!o.out.empty()) {
    const fs::path out = o.out;
    fs::create_directories(out);
    write_text_atomic(out / "scenes.csv", scenes_csv(report));
    write_text_atomic(out / "summary.json", summary_json(report).dump(1) + "\n");
    const std::string note = draw_plots(out);
    if (!note.empty()) report_error(note);
    write_text_atomic(out / "report.html", report_html(report, out, note));
    std::cout << "\nWrote " << (out / "scenes.csv").string() << ", summary.json, report.html\n";
  }
  int failed = 0;
  for (const auto& r : report.runs)
    for (const auto& f : r.frames) failed += f.failed();
  return failed == 0 ? 0 : 1;
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto opts = std::make_shared<EvalOptions>();
  CLI::App* cmd = app.add_subcommand("eval", "score segmentations against ground truth (paper and UOIS metrics)");
  cmd->add_option("DATASET", opts->dataset, "labelled dataset folder (camera.json, depth/, label/, scenes.json)")
      ->required();
  cmd->add_option("--pred", opts->pred, "score the label PNGs in this folder (NAME.png or label/NAME.png) instead of running clutterseg");
  cmd->add_option("--out", opts->out, "write scenes.csv, summary.json, plots/ and report.html here");
  cmd->add_option("--with", opts->with, "also run these methods, e.g. lccp,organized")->delimiter(',');
  cmd->add_option("--sweep", opts->sweep, "NAME=START:STOP:STEP, e.g. theta_c=0.3:0.9:0.1 (also theta_h, or a --dump-config path)");
  cmd->add_flag("--sequence", opts->sequence, "the frames are one sequence of one scene (unless scenes.json names scenes)");
  cmd->add_option("--report-frames", opts->report_frames, "frames pictured in report.html (default 24)");
  cmd->add_option("--subsample", opts->subsample, "keep every N-th row and column of depth and labels, intrinsics scaled (2: a 640x480 set scored as 320x240)")
      ->check(CLI::Range(1, 16));
  opts->camera.add_to(*cmd);
  opts->params.add_to(*cmd);
  cmd->callback([opts] { throw CLI::RuntimeError(run(*opts)); });
}

}  // namespace clutterseg::app
