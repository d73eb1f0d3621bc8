#include "png.hpp"

#include <zlib.h>

#include <array>
#include <cstdint>
#include <vector>

#include "clutterseg/types.hpp"

namespace clutterseg::synth {

namespace {

void put_u32(std::string& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xff));
}

void put_chunk(std::string& out, const char* type, const std::string& data) {
  put_u32(out, static_cast<std::uint32_t>(data.size()));
  const size_t start = out.size();
  out.append(type, 4);
  out.append(data);
  const uLong crc = crc32(0L, reinterpret_cast<const Bytef*>(out.data() + start), static_cast<uInt>(out.size() - start));
  put_u32(out, static_cast<std::uint32_t>(crc));
}

}  // namespace

std::string encode_png(const cv::Mat& image) {
  int colour_type = 0, bit_depth = 8, channels = 1;
  if (image.type() == CV_8UC1) colour_type = 0;
  else if (image.type() == CV_16UC1) bit_depth = 16;
  else if (image.type() == CV_8UC3) { colour_type = 2; channels = 3; }
  else throw Error("encode_png: unsupported image type");
  const int width = image.cols, height = image.rows;
  const size_t row_bytes = static_cast<size_t>(width) * channels * (bit_depth / 8);

  // Raw rows in PNG order (big-endian samples, RGB), each prefixed by its filter type.
  std::vector<unsigned char> raw((row_bytes + 1) * height);
  std::vector<unsigned char> row(row_bytes), previous(row_bytes, 0);
  for (int y = 0; y < height; ++y) {
    if (bit_depth == 16) {
      const auto* src = image.ptr<std::uint16_t>(y);
      for (int x = 0; x < width; ++x) {
        row[2 * x] = static_cast<unsigned char>(src[x] >> 8);
        row[2 * x + 1] = static_cast<unsigned char>(src[x] & 0xff);
      }
    } else if (channels == 3) {
      const auto* src = image.ptr<unsigned char>(y);
      for (int x = 0; x < width; ++x) {
        row[3 * x] = src[3 * x + 2];
        row[3 * x + 1] = src[3 * x + 1];
        row[3 * x + 2] = src[3 * x];
      }
    } else {
      std::copy(image.ptr<unsigned char>(y), image.ptr<unsigned char>(y) + row_bytes, row.begin());
    }
    unsigned char* dst = raw.data() + y * (row_bytes + 1);
    dst[0] = 2;  // "Up": smooth images differ little from the row above
    for (size_t i = 0; i < row_bytes; ++i) dst[i + 1] = static_cast<unsigned char>(row[i] - previous[i]);
    std::swap(row, previous);
  }

  uLongf compressed_size = compressBound(static_cast<uLong>(raw.size()));
  std::string compressed(compressed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(compressed.data()), &compressed_size, raw.data(), static_cast<uLong>(raw.size()), 1) != Z_OK)
    throw Error("encode_png: compression failed");
  compressed.resize(compressed_size);

  std::string out("\x89PNG\r\n\x1a\n", 8);
  std::string header;
  put_u32(header, static_cast<std::uint32_t>(width));
  put_u32(header, static_cast<std::uint32_t>(height));
  header.push_back(static_cast<char>(bit_depth));
  header.push_back(static_cast<char>(colour_type));
  header.append(3, '\0');  // deflate, adaptive filtering, no interlace
  put_chunk(out, "IHDR", header);
  put_chunk(out, "IDAT", compressed);
  put_chunk(out, "IEND", "");
  return out;
}

}  // namespace clutterseg::synth
