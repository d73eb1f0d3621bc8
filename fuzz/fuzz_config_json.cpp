// Parameter JSON (--config, Python, ROS): any text gives valid Params or Error; valid Params survive a
// round trip through --dump-config's JSON.
#include <cstdlib>
#include <string>

#include "clutterseg/config.hpp"
#include "clutterseg/limits.hpp"
#include "clutterseg/types.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace clutterseg;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const Params p = params_from_json(text, "fuzz");
    validate(p);
    const Params again = params_from_json(params_to_json(p), "round trip");
    if (params_to_json(again) != params_to_json(p)) std::abort();
  } catch (const Error&) {
  }
  return 0;
}
