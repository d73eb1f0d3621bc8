// Segmenters behind one interface (frame in, object labels out), so that `bench` and `eval` run
// clutterseg and its PCL peers side by side on the same frames.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "clutterseg/params.hpp"
#include "common.hpp"

namespace clutterseg::app {

struct MethodOutput {
  cv::Mat labels;      // CV_32S object ids, 0 = none (objects only: no table, no background)
  Timings timings_ms;  // per stage, last entry "total"
};

struct Method {
  std::string name;
  // Called on the frames of a sequence in order; a method may keep state between calls.
  std::function<MethodOutput(const Frame&)> run;
};

// "clutterseg" (with `params`, objects-only view), and when built with PCL "lccp" and "organized".
// Throws Error for an unknown name or a baseline this build does not have.
Method make_method(const std::string& name, const Params& params);

// Names make_method accepts in this build.
std::vector<std::string> available_methods();

}  // namespace clutterseg::app
