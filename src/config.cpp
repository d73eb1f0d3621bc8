#include "clutterseg/config.hpp"

#include <cstdint>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "clutterseg/limits.hpp"
#include "clutterseg/types.hpp"

namespace clutterseg {

NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Smoothing, median, temporal, temporal_frames, temporal_band, scene_change_share)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Normals, step_px, smooth_ksize, noise_floor)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Edges, theta, step_px, jump_slope)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Patches, min_size_px, metric_beyond_m, histogram_bins, occupied_share, flat_max_bins, split_band, seam_theta, seam_spread_deg)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Adjacency, radius_px, d_max)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::CutFree, enabled, planes, band, wrong_side_fraction, skip_angle_deg, skip_similar,
                                                split_share)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Convexity, enabled, tolerance, step, concave_weight, step_offset,
                                                top_angle_deg)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Coplanarity, enabled, angle_deg, triples, lines, behind_fraction, behind_tolerance, lines_pass, max_gap,
                                                planar_share, planar_band, front_fraction)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Curvature, enabled, theta_h, open_objects, occluded, line_fit, neighbour_gap_px, concentric,
                                                open_centre, split_inside, inside_crease)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::GraphCut, theta_c)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Remaining, grow_distance, gap_px, tiny_px, min_contact_share, hole_px, shadow_baseline, occluded_jump, in_front, below_tops, apart_on_table, hidden_pairs, hidden_curved,
                                                hidden_coplanar_band, speck_band)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Support, enabled, objects_only, plane_band, pixel_band, table_angle_deg, max_height, contact_distance, region_margin, wall_min_extent, wall_hides_share, curved_bins_ratio, glued_share, enclosed_share)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params::Tracking, enabled, max_missed, max_step, merge_share, max_id)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE_WITH_DEFAULT(Params, smoothing, normals, edges, patches, adjacency, cutfree,
                                                convexity, coplanarity, curvature, graph, remaining, support, seed, threads,
                                                keep_freed_memory, tracking)

namespace {
// A value must have its default's type, and an integer must fit its field: converting 1e40 or 1.5 to
// an int is undefined behaviour, and -1 as the uint64 seed would wrap.
void check_type(const nlohmann::json& value, const nlohmann::json& known, const std::string& key,
                const std::string& what) {
  const auto fail = [&](const std::string& problem) {
    std::string shown = value.dump();
    if (shown.size() > 40) shown = shown.substr(0, 37) + "...";
    throw Error(what + ": parameter '" + key + "' = " + shown + ": " + problem);
  };
  if (known.is_object() && !value.is_object()) fail("must be an object of parameters");
  if (known.is_boolean() && !value.is_boolean()) fail("must be true or false");
  if (known.is_number_float() && !value.is_number()) fail("must be a number");
  if (known.is_number_integer() || known.is_number_unsigned()) {
    if (!value.is_number_integer()) fail("must be an integer");  // also catches floats such as 1e40
    if (known.is_number_unsigned()) {  // the seed
      if (!value.is_number_unsigned()) fail("must be an integer in [0, 18446744073709551615]");
    } else if (value.is_number_unsigned() ? value.get<std::uint64_t>() > std::numeric_limits<int>::max()
                                          : (value.get<std::int64_t>() < std::numeric_limits<int>::min() ||
                                             value.get<std::int64_t>() > std::numeric_limits<int>::max())) {
      fail("is beyond the range of an int");
    }
  }
}

// Lists keys of `given` that the defaults do not have (typos would otherwise be ignored silently).
void check_keys(const nlohmann::json& given, const nlohmann::json& known, const std::string& path,
                const std::string& what) {
  for (const auto& [key, value] : given.items()) {
    if (!known.contains(key)) throw Error(what + ": unknown parameter '" + path + key + "'");
    check_type(value, known.at(key), path + key, what);
    if (value.is_object()) check_keys(value, known.at(key), path + key + ".", what);
  }
}
}  // namespace

std::string params_to_json(const Params& params) { return nlohmann::json(params).dump(2); }

Params params_from_json(const std::string& text, const std::string& what) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    throw Error(what + ": is not valid JSON (" + e.what() + ")");
  }
  if (!j.is_object()) throw Error(what + ": parameters must be a JSON object");
  check_keys(j, nlohmann::json(Params{}), "", what);
  Params params;
  try {
    params = j.get<Params>();
  } catch (const std::exception& e) {
    throw Error(what + ": " + e.what());
  }
  try {
    validate(params);
  } catch (const Error& e) {
    throw Error(what + ": " + e.what());
  }
  return params;
}

Params read_params_file(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw Error(path.string() + ": cannot be opened");
  std::stringstream text;
  text << in.rdbuf();
  return params_from_json(text.str(), path.string());
}

}  // namespace clutterseg
