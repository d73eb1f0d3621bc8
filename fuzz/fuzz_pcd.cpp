// Organized PCD reader (our header check, then PCL's reader): any bytes give a frame or Error.
#include "clutterseg/pcl/pcd.hpp"
#include "fuzz_common.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace clutterseg;
  const auto file = fuzz::write_input(data, size, ".pcd");
  try {
    const PcdFrame f = read_organized_pcd(file);
    check_camera(f.camera, f.depth.cols, f.depth.rows, "fuzz");
  } catch (const Error&) {
  }
  return 0;
}
