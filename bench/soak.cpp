// Soak benchmark: many frames through ONE Segmenter (temporal smoothing on), resident memory sampled.
// A leak or a buffer that grows with the stream shows as a rising RSS after the warm-up.
//   soak DATASET[,DATASET...] FRAMES EVERY OUT.csv [SUBSAMPLE]
// Frames of the given dataset folders (every SUBSAMPLE-th pixel, default 1) are played in a loop; every EVERY frames one CSV row is written:
// frame, RSS [MB], median and max frame time of the block [ms]. Prints a summary line at the end.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "clutterseg/io.hpp"
#include "clutterseg/segmenter.hpp"

namespace {

double rss_mb() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

struct Frame {
  cv::Mat depth;
  clutterseg::Camera camera;
};

}  // namespace

int main(int argc, char** argv) {
  using namespace clutterseg;
  if (argc != 5 && argc != 6) {
    std::cerr << "usage: soak DATASET[,DATASET...] FRAMES EVERY OUT.csv [SUBSAMPLE]\n";
    return 2;
  }
  std::vector<Frame> frames;
  std::stringstream sets(argv[1]);
  for (std::string set; std::getline(sets, set, ',');) {
    Camera camera = read_camera_json(fs::path(set) / "camera.json");
    const int sub = argc == 6 ? std::max(1, std::stoi(argv[5])) : 1;
    camera.fx /= sub, camera.fy /= sub, camera.cx /= sub, camera.cy /= sub;
    camera.width = (camera.width + sub - 1) / sub, camera.height = (camera.height + sub - 1) / sub;
    for (const FrameFiles& f : list_dataset(set)) {
      const cv::Mat full = read_depth_png(f.depth);
      cv::Mat small(camera.height, camera.width, CV_16U);
      for (int y = 0; y < small.rows; ++y)
        for (int x = 0; x < small.cols; ++x) small.at<std::uint16_t>(y, x) = full.at<std::uint16_t>(y * sub, x * sub);
      frames.push_back({small, camera});
    }
  }
  const long total = std::stol(argv[2]), every = std::max(1L, std::stol(argv[3]));
  std::ofstream csv(argv[4]);
  csv << "frame,rss_mb,median_ms,max_ms\n";
  Params params;
  params.threads = 1;  // one core: the soak runs beside other work
  Segmenter segmenter(params);
  std::vector<double> block;
  double first_after_warmup = 0, peak_after_warmup = 0;
  const long warmup = std::min(total / 10, 1000L);
  for (long i = 1; i <= total; ++i) {
    const Frame& f = frames[static_cast<size_t>(i - 1) % frames.size()];
    const auto t0 = std::chrono::steady_clock::now();
    const Result r = segmenter.segment(f.depth, f.camera);
    block.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (r.object_labels.empty()) return 1;
    if (i % every == 0 || i == total) {
      std::sort(block.begin(), block.end());
      const double rss = rss_mb();
      csv << i << "," << rss << "," << block[block.size() / 2] << "," << block.back() << "\n" << std::flush;
      block.clear();
      if (i >= warmup) {
        if (first_after_warmup == 0) first_after_warmup = rss;
        peak_after_warmup = std::max(peak_after_warmup, rss);
      }
    }
  }
  std::printf("soak: %ld frames, RSS after warm-up (frame %ld) %.1f MB, peak after it %.1f MB, at the end %.1f MB\n",
              total, warmup, first_after_warmup, peak_after_warmup, rss_mb());
  return 0;
}
