#include "result_json.hpp"

#include <cmath>

namespace clutterseg::app {

namespace {
nlohmann::json vec(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }
// JSON has no infinity: a cut cost of +inf (single patch, nothing to cut) is written as null.
nlohmann::json finite_or_null(float v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }
}  // namespace

nlohmann::json result_to_json(const Result& r, const std::string& name) {
  nlohmann::json j;
  j["name"] = name;
  j["width"] = r.depth.cols;
  j["height"] = r.depth.rows;
  nlohmann::json timings = nlohmann::json::object();
  for (const auto& [stage, ms] : r.timings_ms) timings[stage] = ms;
  j["timings_ms"] = timings;
  j["patches"] = nlohmann::json::array();
  for (const auto& p : r.patches)
    j["patches"].push_back({{"id", p.id}, {"pixels", p.pixels.size()}, {"centroid", vec(p.centroid)},
                            {"mean_normal", vec(p.mean_normal)}, {"curved", p.curved},
                            {"occupied_bins", p.occupied_bins}});
  j["graph"] = nlohmann::json::array();
  for (const auto& e : r.graph)
    j["graph"].push_back({{"a", e.a + 1}, {"b", e.b + 1}, {"cue", to_string(e.cue)}, {"weight", e.weight},
                          {"convexity", finite_or_null(e.convexity)}});
  j["objects"] = nlohmann::json::array();
  for (const auto& o : r.objects) {
    std::vector<int> patch_ids;
    for (int p : o.patches) patch_ids.push_back(p + 1);
    nlohmann::json axes = nlohmann::json::array();
    for (int c = 0; c < 3; ++c) axes.push_back(vec(o.box.axes.col(c)));
    j["objects"].push_back({{"id", o.id}, {"pixels", o.pixel_count}, {"centroid", vec(o.centroid)},
                            {"box", {{"center", vec(o.box.center)}, {"axes", axes}, {"extents", vec(o.box.extents)}}},
                            {"patches", patch_ids}, {"cut_cost", finite_or_null(o.cut_cost)},
                            {"support", o.support}, {"background", o.background},
                            {"age", o.age}, {"frames_missed", o.frames_missed}, {"split_from", o.split_from},
                            {"merged_with", o.merged_with}});
  }
  // Tracked objects not seen in this frame (docs/TRACKING.md).
  j["hidden_objects"] = nlohmann::json::array();
  for (const auto& h : r.hidden_objects)
    j["hidden_objects"].push_back({{"id", h.id}, {"age", h.age}, {"frames_since_seen", h.frames_since_seen},
                                   {"merged_into", h.merged_into}, {"centroid", vec(h.centroid)}});
  if (r.support_plane)
    j["support_plane"] = {{"normal", vec(r.support_plane->normal)}, {"offset", r.support_plane->offset}};
  else
    j["support_plane"] = nullptr;
  return j;
}

}  // namespace clutterseg::app
