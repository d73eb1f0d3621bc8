// camera.json reader: any bytes give intrinsics that pass check_camera for their own size, or Error.
#include "clutterseg/io.hpp"
#include "clutterseg/params.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace clutterseg;
  const auto file = fuzz::write_input(data, size, ".json");
  try {
    const Camera c = read_camera_json(file);
    check_camera(c, c.width, c.height, "fuzz");
    const PixelScale px(c.fx, c.fy);
    (void)px.length(7), (void)px.area(50), (void)px.odd(5);
  } catch (const Error&) {
  }
  return 0;
}
