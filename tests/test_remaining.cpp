// Paper j): the five rules for remaining pixels, each on a built case.
#include <gtest/gtest.h>

#include "clutterseg/normals.hpp"
#include "clutterseg/remaining.hpp"

using namespace clutterseg;

namespace {

// A 40 x 30 scene at 1 m with a VGA Kinect's angular resolution (2 mm per pixel).
struct Case {
  cv::Mat depth = cv::Mat(30, 40, CV_32F, cv::Scalar(1.0f));
  cv::Mat labels = cv::Mat(30, 40, CV_32S, cv::Scalar(0));
  cv::Mat points() const {
    Camera c;
    c.fx = c.fy = 525;
    c.cx = 20;
    c.cy = 15;
    c.width = 40;
    c.height = 30;
    return depth_to_points(depth, c);
  }
  cv::Mat run(const std::vector<int>& object_of_patch, int num_objects, int tiny = 20) const {
    return assign_remaining(labels, object_of_patch, num_objects, points(), NormalPlanes{}, Params::Remaining{}, tiny);
  }
};

}  // namespace

TEST(Remaining, AssignedPixelsKeepTheirPatchsObject) {
  Case c;
  c.labels.setTo(1);
  c.labels.colRange(20, 40).setTo(2);
  const cv::Mat o = c.run({1, 0}, 2);
  EXPECT_EQ(o.at<int>(5, 5), 2);
  EXPECT_EQ(o.at<int>(5, 30), 1);
}

TEST(Remaining, Rule1NoNeighbourBecomesANewObject) {
  Case c;  // patch 1 on the left; a blob surrounded by missing depth on the right
  c.labels.colRange(0, 10).setTo(1);
  c.depth.colRange(12, 40).setTo(0);
  c.depth(cv::Rect(25, 10, 6, 6)).setTo(0.8f);
  const cv::Mat o = c.run({0}, 1);
  EXPECT_EQ(o.at<int>(12, 27), 2);
  EXPECT_EQ(o.at<int>(5, 35), 0);  // no depth: nothing
  // The same blob below tiny_px is noise: no object.
  EXPECT_EQ(c.run({0}, 1, 40).at<int>(12, 27), 0);
  // Pixels next to the patch (columns 10-11) have it as their only neighbour and are not enclosed.
  EXPECT_EQ(o.at<int>(5, 11), 1);
}

TEST(Remaining, Rule2TinySegmentJoinsItsNeighbour) {
  Case c;
  c.labels.setTo(1);
  c.labels(cv::Rect(18, 12, 3, 3)).setTo(0);   // 9 px, enclosed, 5 cm in front
  c.depth(cv::Rect(18, 12, 3, 3)).setTo(0.95f);
  EXPECT_EQ(c.run({0}, 1, 20).at<int>(13, 19), 1);
  EXPECT_EQ(c.run({0}, 1, 5).at<int>(13, 19), 2);  // not tiny any more: rule 3, enclosed
}

TEST(Remaining, Rule3EnclosedBecomesObjectElseJoins) {
  Case c;
  c.labels.setTo(1);
  c.labels(cv::Rect(15, 10, 8, 8)).setTo(0);   // 64 px hole, 5 cm in front: a small object
  c.depth(cv::Rect(15, 10, 8, 8)).setTo(0.95f);
  EXPECT_EQ(c.run({0}, 1).at<int>(14, 18), 2);
  // The same segment touching the image border is not enclosed: it joins the face.
  Case d;
  d.labels.setTo(1);
  d.labels(cv::Rect(0, 10, 8, 8)).setTo(0);
  d.depth(cv::Rect(0, 10, 8, 8)).setTo(0.95f);
  EXPECT_EQ(d.run({0}, 1).at<int>(14, 3), 1);
  // A shadow (missing depth) beside the object does not break the enclosure.
  Case e = c;
  e.depth(cv::Rect(23, 10, 2, 8)).setTo(0);
  e.labels(cv::Rect(23, 10, 2, 8)).setTo(0);
  EXPECT_EQ(e.run({0}, 1).at<int>(14, 18), 2);
}

TEST(Remaining, Rule4SeveralNeighboursOfOneObjectJoinIt) {
  Case c;  // patches 1 and 2 (both object 0) left and right of a band 3 cm in front
  c.labels.colRange(0, 18).setTo(1);
  c.labels.colRange(22, 40).setTo(2);
  c.depth.colRange(18, 22).setTo(0.97f);
  const cv::Mat o = c.run({0, 0}, 1);
  for (int x = 18; x < 22; ++x) EXPECT_EQ(o.at<int>(15, x), 1);
}

TEST(Remaining, Rule5EveryPixelJoinsTheBestFittingNeighbourPlane) {
  // Object A: plane at 1.0 m (left); object B: plane at 1.1 m (right); between them a band of
  // remaining pixels whose depth ramps from A to B in 6 mm steps (one segment: a bold, blurred edge).
  Case c;
  c.labels.colRange(0, 12).setTo(1);
  c.labels.colRange(28, 40).setTo(2);
  for (int x = 12; x < 40; ++x) c.depth.col(x).setTo(x < 28 ? 1.0 + 0.1 * (x - 11) / 17.0 : 1.1);
  const cv::Mat o = c.run({0, 1}, 2);
  for (int x = 12; x < 20; ++x) EXPECT_EQ(o.at<int>(15, x), 1) << x;
  for (int x = 20; x < 28; ++x) EXPECT_EQ(o.at<int>(15, x), 2) << x;
}

TEST(Remaining, GrowingSeparatesDepthJumps) {
  // Two blobs touching in the image, 5 cm apart in depth, with no neighbouring face: two objects.
  Case c;
  c.depth.setTo(0);
  c.depth(cv::Rect(10, 10, 5, 5)).setTo(1.0f);
  c.depth(cv::Rect(15, 10, 5, 5)).setTo(1.05f);
  const cv::Mat o = c.run({}, 0);
  EXPECT_GT(o.at<int>(12, 12), 0);
  EXPECT_GT(o.at<int>(12, 17), 0);
  EXPECT_NE(o.at<int>(12, 12), o.at<int>(12, 17));
}
