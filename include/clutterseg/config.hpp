// Params <-> JSON, so the CLI, config files, Python and ROS all read the one definition in params.hpp.
#pragma once

#include <filesystem>
#include <string>

#include "clutterseg/params.hpp"

namespace clutterseg {

std::string params_to_json(const Params& params);
// Missing keys keep their defaults; unknown keys are an Error naming `what`.
Params params_from_json(const std::string& text, const std::string& what);
Params read_params_file(const std::filesystem::path& path);

}  // namespace clutterseg
