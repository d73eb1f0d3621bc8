#include "clutterseg/pcl/pcd.hpp"

#include <pcl/PCLPointCloud2.h>
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "clutterseg/limits.hpp"
#include "cloud.hpp"

namespace clutterseg {

namespace {

bool has_field(const pcl::PCLPointCloud2& cloud, const char* name) { return pcl::getFieldIndex(cloud, name) >= 0; }

// Least-squares line t = a * s + b over (s, t) sums.
struct LineFit {
  double n = 0, s = 0, t = 0, ss = 0, st = 0, tt = 0;
  void add(double si, double ti) {
    n += 1, s += si, t += ti, ss += si * si, st += si * ti, tt += ti * ti;
  }
  bool solve(double& a, double& b) const {
    const double det = n * ss - s * s;
    if (n < 3 || det <= 1e-9 * n * n) return false;
    a = (n * st - s * t) / det;
    b = (t - a * s) / n;
    return true;
  }
};

// fx, cx from x/z = u / fx - cx / fx over the valid pixels (and fy, cy likewise from y/z and v).
Camera fit_intrinsics(const pcl::PointCloud<pcl::PointXYZ>& cloud, const std::string& what) {
  LineFit fit_u, fit_v;
  for (int v = 0; v < static_cast<int>(cloud.height); ++v)
    for (int u = 0; u < static_cast<int>(cloud.width); ++u) {
      const auto& p = cloud.at(u, v);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || p.z <= 0) continue;
      fit_u.add(u, p.x / p.z);
      fit_v.add(v, p.y / p.z);
    }
  double au = 0, bu = 0, av = 0, bv = 0;
  if (!fit_u.solve(au, bu) || !fit_v.solve(av, bv) || au <= 0 || av <= 0)
    throw Error(what + ": cannot recover intrinsics (points do not span the image as a pinhole projection)");
  Camera cam;
  cam.fx = 1 / au;
  cam.cx = -bu / au;
  cam.fy = 1 / av;
  cam.cy = -bv / av;
  cam.width = static_cast<int>(cloud.width);
  cam.height = static_cast<int>(cloud.height);
  // A cloud that is not in the sensor frame (e.g. transformed to a robot base) has no such projection.
  double worst = 0;
  for (int v = 0; v < cam.height; v += 4)
    for (int u = 0; u < cam.width; u += 4) {
      const auto& p = cloud.at(u, v);
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) || p.z <= 0) continue;
      worst = std::max({worst, std::abs(cam.fx * p.x / p.z + cam.cx - u), std::abs(cam.fy * p.y / p.z + cam.cy - v)});
    }
  if (worst > 2.0)
    throw Error(what + ": points are not a pinhole projection of their pixels (off by up to " +
                (worst < 1e6 ? std::to_string(static_cast<int>(worst)) : std::string("1000000 or more")) +  // no int overflow
                " px); give the intrinsics or a sensor-frame cloud");
  return cam;
}

// A whole number made only of digits (no sign, no exponent), at most `limit`; -1 otherwise.
std::int64_t whole_number(const std::string& word, std::int64_t limit) {
  std::int64_t v = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (ec != std::errc() || end != word.data() + word.size() || v < 0 || v > limit) return -1;
  return v;
}

// The DATA word or key of a damaged header, shown safely in a one-line message.
std::string printable(const std::string& word) {
  std::string out;
  for (char c : word.substr(0, 24)) out += (c >= 32 && c < 127) ? c : '?';
  return word.size() > 24 ? out + "..." : out;
}

// True when `in` is an LZF stream (liblzf's format, as PCL writes binary_compressed) that decodes to
// exactly `size` bytes: literal runs and back references stay inside the input and the output.
bool lzf_decodes_to(const std::vector<unsigned char>& in, std::size_t size) {
  std::size_t ip = 0, op = 0;
  while (ip < in.size()) {
    const unsigned ctrl = in[ip++];
    if (ctrl < 32) {  // literal run of ctrl + 1 bytes
      const std::size_t len = ctrl + 1;
      if (ip + len > in.size() || op + len > size) return false;
      ip += len, op += len;
    } else {  // back reference
      std::size_t len = ctrl >> 5;
      if (len == 7) {
        if (ip >= in.size()) return false;
        len += in[ip++];
      }
      if (ip >= in.size()) return false;
      const std::size_t back = ((ctrl & 0x1f) << 8) + in[ip++] + 1;
      len += 2;
      if (back > op || op + len > size) return false;
      op += len;
    }
  }
  return op == size;
}

// PCL's reader trusts the header: fuzzed files made it read past its buffers, allocate for 20000 x 20000
// points or decompress into too little memory. So the header is parsed and checked here, against the
// file's size, before PCL reads anything: FIELDS, SIZE, TYPE and COUNT agree and are valid, WIDTH x
// HEIGHT is a frame clutterseg takes (limits.hpp) and equals POINTS, and the body holds the points the
// header declares (binary: points x point size bytes; binary_compressed: the sizes in its 8-byte prefix
// fit the file and the points; ascii: at least one character per value).
void check_header(const std::filesystem::path& path, const std::string& what) {
  const auto bad = [&](const std::string& problem) -> void { throw Error(what + ": not a PCD file (" + problem + ")"); };
  std::error_code ec;
  const std::uintmax_t file_size = std::filesystem::file_size(path, ec);
  if (ec) throw Error(what + ": cannot be read (" + ec.message() + ")");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(what + ": cannot open");
  std::map<std::string, std::vector<std::string>> header;
  std::string line;
  bool data = false;
  // The keys in the order PCL writes them (COUNT and VIEWPOINT may be left out); VERSION first, as PCL's
  // reader needs it.
  static const std::vector<std::string> kKeys = {"VERSION", "FIELDS", "SIZE",  "TYPE", "COUNT",
                                                 "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  size_t next_key = 0;
  for (int i = 0; i < 64 && std::getline(in, line); ++i) {
    if (line.size() > 4096) bad("header line too long");
    if (line.empty()) continue;  // the only lines PCL skips besides comments ("\r" alone is not one)
    if (line.back() == '\r') line.pop_back();
    // PCL splits header lines at tab, CR and space only but reads their first word with `>>`, which also
    // skips vertical tabs and form feeds, so the two disagree on words around such bytes. PCL writes none.
    const auto control = std::find_if(line.begin(), line.end(), [](unsigned char c) { return (c < 0x20 && c != '\t') || c == 0x7f; });
    if (control != line.end()) {
      char code[8];
      std::snprintf(code, sizeof code, "0x%02x", static_cast<unsigned char>(*control));
      bad("header line " + std::to_string(i + 1) + " holds the control character " + code);
    }
    if (!line.empty() && line[0] == '#') continue;
    std::istringstream words(line);
    std::string key, word;
    words >> key;
    // A line of blanks (or a lone CR) ends PCL's header where it stands, and its reader then dereferenced a
    // null pointer (found by fuzz_pcd: lines of tabs or vertical tabs before VERSION).
    if (key.empty()) bad("header line " + std::to_string(i + 1) + " holds only blanks");
    const auto known = std::find(kKeys.begin() + static_cast<std::ptrdiff_t>(next_key), kKeys.end(), key);
    if (known == kKeys.end()) {
      const bool listed = std::find(kKeys.begin(), kKeys.end(), key) != kKeys.end();
      bad(listed ? "header line " + key + " out of order or given twice" : "unknown header line '" + printable(key) + "'");
    }
    if (header.empty() && key != "VERSION") bad("the header does not start with VERSION");
    next_key = static_cast<size_t>(known - kKeys.begin()) + 1;
    std::vector<std::string> values;
    while (words >> word) values.push_back(word);
    header[key] = values;
    if (key == "DATA") { data = true; break; }
  }
  if (!data) bad("no DATA line in the header");
  // PCL's header parser reads on past DATA, skipping empty and comment lines, while lines start with a
  // header keyword: a body that begins like one (COLUMNS, FIELDS, ...), after any comment lines, redefines
  // the fields and PCL reads out of bounds (found by fuzz_pcd, twice). Read the body's first lines as PCL
  // does (at most to the end of the file).
  {
    const std::streampos at = in.tellg();
    std::string next;
    while (std::getline(in, next)) {
      if (next.empty()) continue;
      std::istringstream words(next);
      std::string token;
      words >> token;
      if (token.rfind('#', 0) == 0) continue;
      for (const char* key : {"VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA"})
        if (token.rfind(key, 0) == 0) bad("the body starts like a header line (" + printable(token) + ")");
      break;
    }
    in.clear();
    in.seekg(at);
  }
  const std::uintmax_t body_at = static_cast<std::uintmax_t>(in.tellg());
  const std::uintmax_t body = in.eof() || body_at > file_size ? 0 : file_size - body_at;
  for (const char* key : {"FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT"})
    if (!header.count(key)) bad(std::string("no ") + key + " line");
  const auto& fields = header["FIELDS"];
  const size_t n = fields.size();
  if (n == 0 || n > 256) bad("FIELDS lists " + std::to_string(n) + " fields");
  if (header["SIZE"].size() != n || header["TYPE"].size() != n) bad("FIELDS, SIZE and TYPE differ in length");
  std::vector<std::string> counts = header.count("COUNT") ? header["COUNT"] : std::vector<std::string>(n, "1");
  if (counts.size() != n) bad("COUNT and FIELDS differ in length");
  std::int64_t point_size = 0, values = 0;
  for (size_t f = 0; f < n; ++f) {
    const std::int64_t size = whole_number(header["SIZE"][f], 8), count = whole_number(counts[f], 4096);
    const std::string& type = header["TYPE"][f];
    if (size != 1 && size != 2 && size != 4 && size != 8) bad("field " + printable(fields[f]) + " has SIZE " + printable(header["SIZE"][f]));
    if (type != "I" && type != "U" && type != "F") bad("field " + printable(fields[f]) + " has TYPE " + printable(type));
    if (type == "F" && size != 4 && size != 8) bad("float field " + printable(fields[f]) + " of SIZE " + printable(header["SIZE"][f]));
    if (count < 1) bad("field " + printable(fields[f]) + " has COUNT " + printable(counts[f]));
    point_size += size * count;
    values += count;
  }
  for (const char* axis : {"x", "y", "z"})
    if (std::find(fields.begin(), fields.end(), axis) == fields.end()) throw Error(what + ": PCD has no x/y/z fields");
  if (point_size > 1024) bad("a point of " + std::to_string(point_size) + " bytes");
  if (header["WIDTH"].size() != 1 || header["HEIGHT"].size() != 1) bad("WIDTH and HEIGHT need one number each");
  const std::int64_t width = whole_number(header["WIDTH"][0], kMaxFramePixels), height = whole_number(header["HEIGHT"][0], kMaxFramePixels);
  if (width < 1 || height < 1) bad("WIDTH and HEIGHT must be positive whole numbers");
  check_frame_size(width, height, what);
  const std::int64_t points = width * height;
  if (header.count("POINTS") && (header["POINTS"].size() != 1 || whole_number(header["POINTS"][0], kMaxFramePixels) != points))
    bad("POINTS differs from WIDTH x HEIGHT");
  // PCL converts these words with std::stof and friends, which throw on anything but a number.
  const auto numbers = [&](const char* key, size_t count) {
    if (!header.count(key)) return;
    if (header[key].size() != count) bad(std::string(key) + " needs " + std::to_string(count) + " numbers");
    for (const std::string& word : header[key]) {
      double v = 0;
      const auto [end, err] = std::from_chars(word.data(), word.data() + word.size(), v);
      if (err != std::errc() || end != word.data() + word.size() || !std::isfinite(v))
        bad(std::string(key) + " holds '" + printable(word) + "', not a number");
    }
  };
  numbers("VERSION", 1);
  numbers("VIEWPOINT", 7);
  const auto& kind = header["DATA"];
  if (kind.size() != 1) bad("DATA needs one word");
  const std::uintmax_t payload = static_cast<std::uintmax_t>(points) * static_cast<std::uintmax_t>(point_size);
  if (kind[0] == "binary") {
    if (body < payload)
      bad("body holds " + std::to_string(body) + " bytes, the header declares " + std::to_string(payload));
  } else if (kind[0] == "binary_compressed") {
    unsigned char prefix[8] = {};
    if (body < 8 || !in.read(reinterpret_cast<char*>(prefix), 8)) bad("compressed body without its sizes");
    const auto le32 = [&](int at) {
      return std::uint32_t{prefix[at]} | std::uint32_t{prefix[at + 1]} << 8 | std::uint32_t{prefix[at + 2]} << 16 |
             std::uint32_t{prefix[at + 3]} << 24;
    };
    const std::uint32_t compressed = le32(0), uncompressed = le32(4);
    if (compressed == 0 || compressed > body - 8) bad("compressed size " + std::to_string(compressed) + " does not fit the file");
    if (uncompressed != payload)
      bad("uncompressed size " + std::to_string(uncompressed) + " differs from the " + std::to_string(payload) + " bytes of the points");
    // PCL's LZF decoder trusts its input: the stream is decoded here first, every step bounds-checked.
    std::vector<unsigned char> packed(compressed);
    if (!in.read(reinterpret_cast<char*>(packed.data()), compressed)) bad("compressed body cut short");
    if (!lzf_decodes_to(packed, uncompressed)) bad("compressed body is not a valid LZF stream of the points");
  } else if (kind[0] == "ascii") {
    if (body < static_cast<std::uintmax_t>(points) * static_cast<std::uintmax_t>(values))
      bad("ascii body too short for " + std::to_string(points) + " points");
  } else {
    bad("DATA " + printable(kind[0]) + " (ascii, binary or binary_compressed)");
  }
}

}  // namespace

PcdFrame read_organized_pcd(const std::filesystem::path& path, const std::optional<Camera>& camera) {
  const std::string what = path.string();
  if (!std::filesystem::exists(path)) throw Error(what + ": no such file");
  if (std::filesystem::is_directory(path)) throw Error(what + ": is a folder, not a PCD file");

  check_header(path, what);
  pcl::PCLPointCloud2 blob;
  {
    baselines::QuietPcl quiet;
    pcl::PCDReader reader;
    try {
      if (reader.read(what, blob) < 0) throw Error(what + ": not a readable PCD file");
    } catch (const Error&) {
      throw;
    } catch (const std::exception& e) {  // PCL's reader throws what its conversions throw
      throw Error(what + ": not a readable PCD file (" + printable(e.what()) + ")");
    }
  }
  if (!has_field(blob, "x") || !has_field(blob, "y") || !has_field(blob, "z"))
    throw Error(what + ": PCD has no x/y/z fields");
  if (blob.height <= 1)
    throw Error(what + ": PCD is not organized (height " + std::to_string(blob.height) +
                "); an image-shaped cloud is needed");

  pcl::PointCloud<pcl::PointXYZ> xyz;
  pcl::fromPCLPointCloud2(blob, xyz);
  const int width = static_cast<int>(xyz.width), height = static_cast<int>(xyz.height);

  PcdFrame frame;
  frame.depth = cv::Mat(height, width, CV_32F, cv::Scalar(0));
  int valid = 0;
  for (int v = 0; v < height; ++v) {
    auto* row = frame.depth.ptr<float>(v);
    for (int u = 0; u < width; ++u) {
      const auto& p = xyz.at(u, v);
      if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z) && p.z > 0) {
        row[u] = p.z;
        ++valid;
      }
    }
  }
  if (valid == 0) throw Error(what + ": PCD holds no valid point (all NaN)");

  if (has_field(blob, "rgb") || has_field(blob, "rgba")) {
    pcl::PointCloud<pcl::PointXYZRGBA> colored;
    pcl::fromPCLPointCloud2(blob, colored);
    frame.color = cv::Mat(height, width, CV_8UC3);
    for (int v = 0; v < height; ++v) {
      auto* row = frame.color.ptr<cv::Vec3b>(v);
      for (int u = 0; u < width; ++u) {
        const auto& p = colored.at(u, v);
        row[u] = cv::Vec3b(p.b, p.g, p.r);
      }
    }
  }

  if (camera) {
    check_camera(*camera, width, height, what);
    frame.camera = *camera;
  } else {
    frame.camera = fit_intrinsics(xyz, what);
  }
  return frame;
}

}  // namespace clutterseg
