#pragma once

#include <nlohmann/json.hpp>

#include "clutterseg/segmenter.hpp"

namespace clutterseg::app {

// The per-frame JSON summary: timings, patches, graph, objects, support plane.
nlohmann::json result_to_json(const Result& result, const std::string& name);

}  // namespace clutterseg::app
