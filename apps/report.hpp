// What `clutterseg eval` found, and the ways it is shown: the summary tables (stdout and HTML), the
// per-frame CSV, summary.json, matplotlib plots and the self-contained report.html.
#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "clutterseg/error_breakdown.hpp"
#include "clutterseg/metrics.hpp"
#include "clutterseg/params.hpp"
#include "clutterseg/tracking_metrics.hpp"

namespace clutterseg::app {

namespace fs = std::filesystem;

struct FrameRecord {
  std::string frame, family, scene;
  FrameScores scores;
  ErrorBreakdown errors;  // why the scores are what they are
  double total_ms = FrameScores::kNaN;
  std::string error;  // non-empty: the frame failed and has no scores
  bool failed() const { return !error.empty(); }
};

// Scores of one family (or "all"): per scene the mean of its frames, then mean and std over scenes.
struct GroupSummary {
  std::string family;
  int frames = 0;    // frames with scores
  int scenes = 0;    // distinct scenes among them
  int failed = 0;    // frames that failed
  int unscored = 0;  // frames without ground-truth objects
  std::array<MeanStd, kScoreNames.size()> scores;
  std::array<MeanStd, kBreakdownNames.size()> errors;  // averaged like the scores
  int merged_objects = 0, split_objects = 0, missed_objects = 0;  // summed over the frames
};

// A thumbnail row of the report: one frame's images (JPEG bytes).
struct GalleryFrame {
  std::string frame, family;
  std::string image, ground_truth;  // colour (or depth) image; ground truth over it
};

struct RunRecord {
  std::string method;                                  // make_method name, or "pred"
  std::string label;                                   // e.g. "clutterseg theta_c=0.3"
  std::vector<std::pair<std::string, double>> setting; // swept parameter and value, if any
  std::vector<FrameRecord> frames;
  std::vector<GroupSummary> groups;                    // "all" first, then the families
  Timings mean_timings_ms;                             // mean per stage over frames, "total" last
  std::vector<std::pair<std::string, std::string>> predictions;  // frame -> JPEG of the prediction
  bool best = false;   // best Overlap F of its sweep
  bool shown = false;  // the run of its method shown in plots and pictures (default or best)
  TrackingScores tracking;  // ids across the frames of each scene, summed over scenes (docs/EVAL.md)
  const GroupSummary& all() const { return groups.front(); }
};

struct EvalReport {
  std::string dataset;
  std::string command;
  int frames = 0, scenes = 0;
  int boundary_tolerance_px = 0;
  std::optional<std::string> sweep_parameter;  // as the user typed it, e.g. "theta_c"
  std::string params_json;                     // parameters of the clutterseg runs
  std::vector<RunRecord> runs;
  std::vector<GalleryFrame> gallery;
};

// Summaries of the frames of a run: "all", then one group per family in first-seen order.
std::vector<GroupSummary> summarize(const std::vector<FrameRecord>& frames);

// Markdown tables: one per run (families as rows), then the sweep table with the best value marked.
std::string format_tables(const EvalReport& report);

nlohmann::json summary_json(const EvalReport& report);
std::string scenes_csv(const EvalReport& report);

// Runs scripts/report_plots.py (compiled into the tool) over OUT; returns "" on success or the one
// line the report shows instead of the plots.
std::string draw_plots(const fs::path& out);

// The self-contained page: tables, the plots found in OUT/plots, pictures per frame.
std::string report_html(const EvalReport& report, const fs::path& out, const std::string& plot_note);

std::string base64(const std::string& bytes);

}  // namespace clutterseg::app
