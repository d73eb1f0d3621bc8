// Beyond the paper: a patch split along a weak crease or a small step across it (seams.hpp), and the
// step between parallel faces that the contact cue reads from their offset (contact.hpp). Tiny exact
// images first, then a stacked pair of boxes seen through the Kinect v1 model, the case they are for.
#include <gtest/gtest.h>

#include "clutterseg/contact.hpp"
#include "clutterseg/seams.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/synth/sensor.hpp"
#include "scenes.hpp"

using namespace clutterseg;

namespace {

// One patch of w x h pixels filling the image (label 1), edge value 1, normals facing the camera.
struct Image {
  int w, h;
  cv::Mat labels, value, edges, points;
  std::optional<Plane> plane;
  NormalPlanes normals;
  Patch patch;
  Image(int w_, int h_) : w(w_), h(h_) {
    labels = cv::Mat(h, w, CV_32S, cv::Scalar(1));
    value = cv::Mat(h, w, CV_32F, cv::Scalar(1.f));
    edges = cv::Mat(h, w, CV_8U, cv::Scalar(0));
    normals = {cv::Mat(h, w, CV_32F, cv::Scalar(0.f)), cv::Mat(h, w, CV_32F, cv::Scalar(0.f)),
               cv::Mat(h, w, CV_32F, cv::Scalar(-1.f))};
    points = cv::Mat(h, w, CV_32FC3, cv::Scalar(0, 0, 1));  // a plane 1 m in front of the camera
    patch.id = 1;
    patch.bbox = cv::Rect(0, 0, w, h);
    for (int i = 0; i < w * h; ++i) patch.pixels.push_back(i);
  }
  void band(int y0, int y1, int x0, int x1, float v) { value(cv::Range(y0, y1), cv::Range(x0, x1)).setTo(v); }
  int split(const Params::Patches& params = {}, int min_px = 100) {
    return split_at_seams(edges, {patch}, labels, value, normals, params, min_px, points, plane, Params::Support{});
  }
  int edge_rows(int y0, int y1) const { return cv::countNonZero(edges(cv::Range(y0, y1), cv::Range::all())); }
};

}  // namespace

TEST(Seams, AWeakBandAcrossAPatchBecomesEdgesAndNothingElse) {
  Image im(40, 30);
  im.band(14, 17, 0, 40, 0.93f);  // a crease too shallow for edges.theta (0.89), across the whole patch
  im.band(5, 7, 10, 14, 0.94f);   // a weak speck inside one part: no band between two parts
  EXPECT_EQ(im.split(), 3 * 40);
  EXPECT_EQ(im.edge_rows(14, 17), 3 * 40);
  EXPECT_EQ(cv::countNonZero(im.edges), 3 * 40);
}

TEST(Seams, ABandWithAGapOrSmallPartsOrTheSwitchOffSplitsNothing) {
  Image gap(40, 30);
  gap.band(14, 17, 0, 34, 0.93f);  // six columns of the crease as strong as the faces: one part
  EXPECT_EQ(gap.split(), 0);
  Image small(40, 30);
  small.band(2, 5, 0, 40, 0.93f);  // the part above holds 2 x 40 pixels, fewer than min_px
  EXPECT_EQ(small.split(), 0);
  Image off(40, 30);
  off.band(14, 17, 0, 40, 0.93f);
  Params::Patches params;
  params.seam_theta = 0;
  EXPECT_EQ(off.split(params), 0);
  params.seam_theta = 0.92;  // the band is not weak at this threshold
  EXPECT_EQ(off.split(params), 0);
  EXPECT_EQ(cv::countNonZero(off.edges), 0);
}

TEST(Seams, CurvedPartsAreNotSplitUnlessATablePatchHoldsThem) {
  // The lower part's normals turn by +-30 deg across its columns (a cylinder's wall): its mean angle to
  // its mean normal is about 15.5 deg, more than seam_spread_deg.
  Image im(40, 30);
  im.band(14, 17, 0, 40, 0.93f);
  for (int y = 17; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      const float a = static_cast<float>((x - 19.5) / 19.5 * 30 * M_PI / 180);
      im.normals[0].at<float>(y, x) = std::sin(a);
      im.normals[2].at<float>(y, x) = -std::cos(a);
    }
  EXPECT_EQ(im.split(), 0);
  // A table patch (the plane z = 1 m facing the camera): two pieces of table stay one patch, ...
  im.patch.table = true;
  im.plane = Plane{Eigen::Vector3f(0, 0, -1), 1.f};
  EXPECT_EQ(im.split(), 0);
  // ... an object's part left in it, 3 cm above the table, is cut off whatever its shape.
  im.points(cv::Range(17, 30), cv::Range::all()).setTo(cv::Scalar(0, 0, 0.97));
  EXPECT_EQ(im.split(), 3 * 40);
}

TEST(Seams, ParallelFacesOffsetAlongTheirNormalMeetInAStep) {
  // Two patches facing the camera, their contacts 1 cm apart sideways; pair 0-1 offset by 6 mm in depth
  // at 1 m (a step the contact normals read as convex: they are tilted by the smoothing), pair 2-3 on
  // one plane with the same normals.
  cv::Mat points(1, 4, CV_32FC3), nx(1, 4, CV_32F), ny(1, 4, CV_32F), nz(1, 4, CV_32F);
  const auto set = [&](int i, Eigen::Vector3f p, Eigen::Vector3f n) {
    points.at<cv::Vec3f>(0, i) = {p.x(), p.y(), p.z()};
    n.normalize();
    nx.at<float>(0, i) = n.x(); ny.at<float>(0, i) = n.y(); nz.at<float>(0, i) = n.z();
  };
  set(0, {-0.005f, 0, 1.0f}, {-0.3f, 0, -1});
  set(1, {0.005f, 0, 1.006f}, {0.3f, 0, -1});
  set(2, {-0.005f, 0, 1.0f}, {-0.3f, 0, -1});
  set(3, {0.005f, 0, 1.0f}, {0.3f, 0, -1});
  std::vector<Contact> contacts;
  for (int pair = 0; pair < 2; ++pair)
    for (int k = 0; k < 5; ++k) contacts.push_back({2 * pair, 2 * pair + 1, 2 * pair, 2 * pair + 1});
  std::vector<Patch> patches(4);
  for (Patch& p : patches) p.mean_normal = Eigen::Vector3f(0, 0, -1);
  const NormalPlanes normals{nx, ny, nz};
  const Params::Convexity params;
  const auto without = classify_junctions(contacts, points, normals, params);
  ASSERT_EQ(without.size(), 2u);
  EXPECT_EQ(without[0].kind, Junction::Convex);  // the paper's view of the contacts alone
  const auto with = classify_junctions(contacts, points, normals, params, patches);
  EXPECT_EQ(with[0].kind, Junction::Step);
  EXPECT_EQ(with[1].kind, Junction::Convex);  // no offset: the contact normals decide, as before
  // Faces 20 deg apart are not parallel: their offset says nothing.
  patches[1].mean_normal = Eigen::Vector3f(std::sin(0.35f), 0, -std::cos(0.35f));
  EXPECT_EQ(classify_junctions(contacts, points, normals, params, patches)[0].kind, Junction::Convex);
  Params::Convexity off;
  off.step_offset = 0;
  patches[1].mean_normal = Eigen::Vector3f(0, 0, -1);
  EXPECT_EQ(classify_junctions(contacts, points, normals, off, patches)[0].kind, Junction::Convex);
}
