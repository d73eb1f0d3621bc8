// Shared by the libFuzzer harnesses: the readers take paths, so the input goes to a file first.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace clutterseg::fuzz {

// A file of this process in the temporary folder, holding the input, with the given extension.
inline std::filesystem::path write_input(const std::uint8_t* data, std::size_t size, const std::string& extension) {
  static const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("clutterseg-fuzz-" + std::to_string(getpid()) + extension);
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return file;
}

}  // namespace clutterseg::fuzz
