// Segmentation of real organized clouds (pcl-organized, a Kinect on an office floor): objects that only
// these frames show. Held to docs/RESULTS.md, section 15e.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>

#include "clutterseg/objects.hpp"
#include "clutterseg/pcl/pcd.hpp"
#include "clutterseg/segmenter.hpp"

namespace fs = std::filesystem;
using namespace clutterseg;

// The open laptop's lid (one flat patch, 0.44 x 0.40 m, upright on the floor) was dropped as a wall in all
// three frames; it must be one object, and the floor in front of it none.
TEST(PcdQuality, TheLaptopLidIsAnObjectNotAWall) {
  const fs::path dir = fs::path(CLUTTERSEG_DATA_DIR) / "pcl-organized";
  for (const char* name : {"frame_20121214T142255.814212.pcd", "frame_20121214T142256.068683.pcd",
                           "frame_20121214T142256.332395.pcd"}) {
    SCOPED_TRACE(name);
    const PcdFrame frame = read_organized_pcd(dir / name);
    Params p;
    p.smoothing.temporal = false;
    const Result r = segment(frame.depth, frame.camera, p);
    const cv::Mat view = objects_only(r.object_labels, r.objects);
    std::map<int, int> count;  // the lid's middle, around the logo
    for (int y = 180; y < 280; ++y)
      for (int x = 170; x < 330; ++x) ++count[view.at<int>(y, x)];
    const auto best = std::max_element(count.begin(), count.end(), [](auto& a, auto& b) { return a.second < b.second; });
    EXPECT_NE(best->first, 0) << "the lid is labelled floor or background";
    EXPECT_GT(best->second, 0.95 * 100 * 160);
    EXPECT_EQ(cv::countNonZero(view(cv::Rect(100, 400, 400, 60))), 0) << "floor in front of the laptop labelled an object";
  }
}
