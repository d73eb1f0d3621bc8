// Pre-segmentation (paper a-c) on analytic depth images: what the paper says each stage must do.
#include <gtest/gtest.h>

#include <algorithm>

#include <opencv2/imgproc.hpp>

#include "clutterseg/edges.hpp"
#include "clutterseg/normals.hpp"
#include "clutterseg/patches.hpp"
#include "clutterseg/segmenter.hpp"
#include "clutterseg/smoothing.hpp"
#include "clutterseg/synth/dataset.hpp"
#include "scenes.hpp"

using namespace clutterseg;

TEST(Median, KeepsInvalidPixelsInvalidAndIgnoresThem) {
  cv::Mat d(5, 5, CV_32F, cv::Scalar(1.0f));
  d.at<float>(2, 2) = 0;   // a hole stays a hole
  d.at<float>(1, 1) = 0;   // a neighbour hole does not drag the median to 0
  d.at<float>(3, 3) = 5;   // a spike is removed
  const cv::Mat m = median_depth(d);
  EXPECT_EQ(m.at<float>(2, 2), 0.f);
  EXPECT_EQ(m.at<float>(1, 1), 0.f);
  EXPECT_FLOAT_EQ(m.at<float>(3, 3), 1.f);
  EXPECT_FLOAT_EQ(m.at<float>(1, 2), 1.f);
  EXPECT_FLOAT_EQ(m.at<float>(0, 0), 1.f);
}

TEST(Median, IsTheMedianOfTheValidNeighboursEverywhere) {
  // Noisy depth with a third of the pixels missing: every pixel, at the border, next to holes (redone
  // eight at a time or one at a time) and in the open (OpenCV's median), against a plain reference.
  cv::Mat d(37, 45, CV_32F);
  cv::RNG rng(5);
  rng.fill(d, cv::RNG::UNIFORM, 0.5, 2.0);
  cv::Mat holes(d.size(), CV_32F);
  rng.fill(holes, cv::RNG::UNIFORM, 0.0, 1.0);
  d.setTo(0, holes < 0.33);
  const cv::Mat m = median_depth(d);
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) {
      std::vector<float> valid;
      for (int yy = std::max(y - 1, 0); yy <= std::min(y + 1, d.rows - 1); ++yy)
        for (int xx = std::max(x - 1, 0); xx <= std::min(x + 1, d.cols - 1); ++xx)
          if (d.at<float>(yy, xx) > 0) valid.push_back(d.at<float>(yy, xx));
      std::sort(valid.begin(), valid.end());
      const float expected = d.at<float>(y, x) > 0 ? valid[valid.size() / 2] : 0.f;
      ASSERT_EQ(m.at<float>(y, x), expected) << "at (" << x << ", " << y << ")";
    }
}

TEST(EdgeValue, IsTheMeanOverTheNeighboursInsideTheImageEverywhere) {
  // Random unit normals, some missing: every pixel, the top and bottom rows (summed by the row kernel
  // with rows of zeros) and the left and right columns (one at a time) included, against a plain loop.
  constexpr int kStep = 2;
  for (const cv::Size size : {cv::Size(29, 23), cv::Size(7, 4)}) {
    NormalPlanes n;
    cv::RNG rng(9);
    for (auto& plane : n) {
      plane.create(size, CV_32F);
      rng.fill(plane, cv::RNG::UNIFORM, -1.0, 1.0);
    }
    cv::Mat norm;
    cv::magnitude(n[0].mul(n[0]) + n[1].mul(n[1]), n[2], norm);
    cv::Mat missing(size, CV_32F);
    rng.fill(missing, cv::RNG::UNIFORM, 0.0, 1.0);
    for (auto& plane : n) {
      plane /= norm;
      plane.setTo(0, missing < 0.1);
    }
    const cv::Mat value = normal_edge_value(n, kStep);
    for (int y = 0; y < size.height; ++y)
      for (int x = 0; x < size.width; ++x) {
        double sum = 0;
        int count = 0;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx * kStep, yy = y + dy * kStep;
            if ((dx == 0 && dy == 0) || xx < 0 || yy < 0 || xx >= size.width || yy >= size.height) continue;
            double dot = 0;
            for (const auto& plane : n) dot += plane.at<float>(y, x) * plane.at<float>(yy, xx);
            sum += std::abs(dot);
            ++count;
          }
        ASSERT_NEAR(value.at<float>(y, x), sum / count, 1e-5) << size << " at (" << x << ", " << y << ")";
      }
  }
}

TEST(Temporal, AveragesStaticNoiseAndKeepsMotion) {
  Params::Smoothing p;
  TemporalSmoother t;
  cv::RNG rng(1);
  cv::Mat last;
  for (int i = 0; i < 6; ++i) {
    cv::Mat d(20, 20, CV_32F);
    rng.fill(d, cv::RNG::NORMAL, 1.0, 0.001);  // 1 m, 1 mm noise: inside the 3 mm band
    last = t.push(d, p);
  }
  cv::Scalar mean, sd;
  cv::meanStdDev(last, mean, sd);
  EXPECT_LT(sd[0], 0.0007);  // about 1/sqrt(6) of the input noise
  // A box appears 10 cm in front: the newest depth is taken, not a blend (no motion blur).
  cv::Mat moved(20, 20, CV_32F, cv::Scalar(0.9f));
  const cv::Mat out = t.push(moved, p);
  EXPECT_FLOAT_EQ(out.at<float>(10, 10), 0.9f);
}

// A folder of unrelated frames, or a cut in a video: depth of one scene must never be averaged into the
// next. An object moving over a third of the image is the same scene and keeps the window.
TEST(Temporal, ANewSceneEmptiesTheWindowAMovingObjectDoesNot) {
  Params::Smoothing p;
  TemporalSmoother t;
  for (int i = 0; i < 3; ++i) t.push(cv::Mat(40, 40, CV_32F, cv::Scalar(1.0f)), p);
  cv::Mat moving(40, 40, CV_32F, cv::Scalar(1.0f));
  moving(cv::Rect(0, 0, 40, 13)).setTo(0.8f);  // a third of the pixels 20 cm closer
  t.push(moving, p);
  EXPECT_EQ(t.size(), 4);
  EXPECT_FALSE(scene_changed(moving, cv::Mat(40, 40, CV_32F, cv::Scalar(1.0f)), p));
  const cv::Mat other(40, 40, CV_32F, cv::Scalar(1.5f));  // another scene: everything 50 cm farther
  EXPECT_TRUE(scene_changed(moving, other, p));
  const cv::Mat out = t.push(other, p);
  EXPECT_EQ(t.size(), 1);
  EXPECT_FLOAT_EQ(out.at<float>(30, 30), 1.5f);
  EXPECT_TRUE(scene_changed(other, cv::Mat(20, 20, CV_32F, cv::Scalar(1.5f)), p));  // another size
}

TEST(Normals, PlaneFacingTheCameraAndTiltedPlane) {
  Camera cam = synth::default_camera(64, 48);
  cv::Mat flat(48, 64, CV_32F, cv::Scalar(1.0f));
  NormalPlanes n = compute_normals(flat, cam, 1, 5, 0.1f);
  cv::Vec3f c(n[0].at<float>(24, 32), n[1].at<float>(24, 32), n[2].at<float>(24, 32));
  EXPECT_NEAR(c[2], -1.0, 1e-4);
  // Plane z = 1 + 0.5 y (tilted about the x axis): normal (0, -0.5, 1) normalised, facing the camera.
  cv::Mat tilted(48, 64, CV_32F);
  for (int v = 0; v < 48; ++v)
    for (int u = 0; u < 64; ++u) {
      const double ry = (v - cam.cy) / cam.fy;  // z = 1 + 0.5 * ry * z
      tilted.at<float>(v, u) = static_cast<float>(1.0 / (1.0 - 0.5 * ry));
    }
  n = compute_normals(tilted, cam, 1, 5, 0.1f);
  c = cv::Vec3f(n[0].at<float>(24, 32), n[1].at<float>(24, 32), n[2].at<float>(24, 32));
  const Eigen::Vector3f expected = Eigen::Vector3f(0, 0.5f, -1).normalized();
  EXPECT_NEAR(c[1], expected.y(), 1e-3);
  EXPECT_NEAR(c[2], expected.z(), 1e-3);
}

TEST(Normals, SmoothingIsOpenCVsGaussianEverywhere) {
  // The normals' Gaussian is our own separable filter (OpenCV's float row filter is slow at more than 5
  // taps). Against cv::GaussianBlur (BORDER_REPLICATE) of the unsmoothed normals, renormalised, at every
  // pixel, borders included: on a noisy surface with holes and jumps, at a width that is no multiple of
  // the vector width, for unrolled sizes (3 to 17) and one beyond them (19), and kernels taller or
  // wider than the image.
  cv::RNG rng(11);
  for (const cv::Size size : {cv::Size(45, 37), cv::Size(64, 7), cv::Size(5, 40), cv::Size(1, 1)}) {
    cv::Mat depth(size, CV_32F);
    rng.fill(depth, cv::RNG::UNIFORM, 0.9, 1.1);
    cv::Mat holes(size, CV_32F);
    rng.fill(holes, cv::RNG::UNIFORM, 0.0, 1.0);
    depth.setTo(0, holes < 0.1);
    if (size.width > 1) depth(cv::Rect(size.width / 2, 0, size.width / 2, size.height)) += 0.3f;  // a jump
    const Camera cam = synth::default_camera(size.width, size.height);
    const NormalPlanes raw = compute_normals(depth, cam, 1, 1, 0.05f);
    for (const int ksize : {3, 5, 9, 17, 19}) {
      const NormalPlanes n = compute_normals(depth, cam, 1, ksize, 0.05f);
      NormalPlanes reference;
      for (int c = 0; c < 3; ++c)
        cv::GaussianBlur(raw[c], reference[c], cv::Size(ksize, ksize), 0, 0, cv::BORDER_REPLICATE);
      for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
          Eigen::Vector3f expected(reference[0].at<float>(y, x), reference[1].at<float>(y, x), reference[2].at<float>(y, x));
          expected = depth.at<float>(y, x) > 0 && expected.norm() > 1e-6f ? expected.normalized() : Eigen::Vector3f::Zero();
          for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(n[c].at<float>(y, x), expected[c], 2e-5f)
                << "ksize " << ksize << ", size " << size << ", at (" << x << ", " << y << "), plane " << c;
        }
    }
  }
}

TEST(Edges, PlaneHasNoEdgesAndAStepHasOne) {
  Camera cam = synth::default_camera(64, 48);
  cv::Mat d(48, 64, CV_32F, cv::Scalar(1.0f));
  Params::Edges pe;
  auto edges_of = [&](const cv::Mat& depth) {
    const cv::Mat pts = depth_to_points(depth, cam);
    const float jump = relative_jump_limit(pe, 1, cam);
    return edge_mask(normal_edge_value(compute_normals(depth, cam, 1, 5, jump), 1), depth, pe.theta, jump);
  };
  EXPECT_EQ(cv::countNonZero(edges_of(d)), 0);
  d(cv::Rect(32, 0, 32, 48)).setTo(0.8f);  // a 20 cm step
  const cv::Mat e = edges_of(d);
  for (int v = 0; v < 48; ++v) EXPECT_TRUE(e.at<uchar>(v, 31) || e.at<uchar>(v, 32)) << "row " << v;
  EXPECT_EQ(e.at<uchar>(24, 10), 0);
  EXPECT_EQ(e.at<uchar>(24, 50), 0);
}

TEST(Patches, BoxOnPlaneGivesTableAndVisibleFaces) {
  const auto scene = scenes::box_on_plane();
  const auto truth = scene.render();
  Params p;
  p.smoothing.temporal = false;
  const Result r = segment(truth.depth, scene.camera, p);
  // Table + top + two visible side faces: each a patch of its own.
  EXPECT_GE(r.patches.size(), 3u);
  EXPECT_LE(r.patches.size(), 4u);
  // No patch mixes box and table pixels.
  for (const auto& patch : r.patches) {
    int on_box = 0;
    for (int i : patch.pixels) on_box += truth.labels.ptr<int>()[i] == 1;
    EXPECT_TRUE(on_box == 0 || on_box == static_cast<int>(patch.pixels.size())) << "patch " << patch.id;
  }
  for (const auto& patch : r.patches) EXPECT_FALSE(patch.curved) << "patch " << patch.id;
}

TEST(Patches, SmallComponentsAreDropped) {
  cv::Mat edges(40, 40, CV_8U, cv::Scalar(0));
  edges.row(20).setTo(255);
  edges(cv::Rect(0, 0, 5, 5)).setTo(255);
  edges.at<uchar>(2, 2) = 0;  // a 1-pixel island
  cv::Mat depth(40, 40, CV_32F, cv::Scalar(1));
  const NormalPlanes nrm = {cv::Mat(40, 40, CV_32F, cv::Scalar(0)), cv::Mat(40, 40, CV_32F, cv::Scalar(0)),
                            cv::Mat(40, 40, CV_32F, cv::Scalar(-1))};
  const Patches p = extract_patches(edges, depth, synth::default_camera(40, 40), nrm, Params::Patches{}, 10);
  EXPECT_EQ(p.patches.size(), 2u);
  EXPECT_EQ(p.labels.at<int>(2, 2), 0);
  // Inputs that do not fit each other are refused, not read out of bounds.
  EXPECT_THROW(extract_patches(edges, depth(cv::Rect(0, 0, 40, 30)), synth::default_camera(40, 40), nrm, {}, 10), Error);
}

// A face's pixel count falls with z^2: beyond metric_beyond_m a component needs only the metric area
// min_size covers there, and never less than a quarter of min_size pixels.
TEST(Patches, AFarFaceNeedsOnlyTheMetricAreaOfMinSize) {
  const auto patches_of = [](double z, int side, double beyond_m) {
    cv::Mat edges(40, 40, CV_8U, cv::Scalar(255));
    edges(cv::Rect(5, 5, side, side)).setTo(0);  // one face of side x side pixels, edges around it
    const cv::Mat depth(40, 40, CV_32F, cv::Scalar(z));
    const NormalPlanes nrm = {cv::Mat(40, 40, CV_32F, cv::Scalar(0)), cv::Mat(40, 40, CV_32F, cv::Scalar(0)),
                              cv::Mat(40, 40, CV_32F, cv::Scalar(-1))};
    Params::Patches params;
    params.metric_beyond_m = beyond_m;
    return extract_patches(edges, depth, synth::default_camera(40, 40), nrm, params, 200).patches.size();
  };
  EXPECT_EQ(patches_of(2.0, 10, 1.3), 1u);   // 100 px at 2 m cover what 237 px cover at 1.3 m
  EXPECT_EQ(patches_of(2.0, 10, 0.0), 0u);   // off: min_size pixels at every depth
  EXPECT_EQ(patches_of(1.5, 10, 1.3), 0u);   // 100 px at 1.5 m: 133 px at 1.3 m, too small
  EXPECT_EQ(patches_of(1.0, 10, 1.3), 0u);   // nearer than 1.3 m: pixels only
  EXPECT_EQ(patches_of(1.0, 15, 1.3), 1u);   // 225 px
  EXPECT_EQ(patches_of(4.0, 7, 1.3), 0u);    // 49 px, below a quarter of min_size however far
}

TEST(Patches, AreTheFourConnectedComponentsOfTheNonEdgePixels) {
  // Patches come from runs of non-edge pixels joined across rows. With a minimum size of 1 every
  // component is a patch, and the patch image must be OpenCV's 4-connected labelling, numbering
  // included (raster order of the first pixel): on random masks of every density, on a checkerboard
  // (diagonal neighbours only: every pixel alone), on combs and spirals whose runs merge late, and on
  // images of one row or one column.
  const auto check = [](const cv::Mat& edges, const std::string& what) {
    cv::Mat reference;
    const int count = cv::connectedComponents(edges == 0, reference, 4, CV_32S);
    const cv::Mat depth(edges.size(), CV_32F, cv::Scalar(1));
    const NormalPlanes nrm = {cv::Mat(edges.size(), CV_32F, cv::Scalar(0)), cv::Mat(edges.size(), CV_32F, cv::Scalar(0)),
                              cv::Mat(edges.size(), CV_32F, cv::Scalar(-1))};
    const Patches p = extract_patches(edges, depth, synth::default_camera(edges.cols, edges.rows), nrm, {}, 1);
    EXPECT_EQ(static_cast<int>(p.patches.size()), count - 1) << what;
    EXPECT_EQ(cv::countNonZero(p.labels != reference), 0) << what;
    for (const Patch& patch : p.patches)
      EXPECT_EQ(static_cast<int>(patch.pixels.size()), cv::countNonZero(reference == patch.id)) << what;
  };
  cv::RNG rng(17);
  for (const double density : {0.05, 0.3, 0.45, 0.6, 0.9}) {
    cv::Mat noise(53, 71, CV_32F);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    check(noise < density, "random, density " + std::to_string(density));
  }
  cv::Mat checkerboard(20, 24, CV_8U);
  for (int y = 0; y < checkerboard.rows; ++y)
    for (int x = 0; x < checkerboard.cols; ++x) checkerboard.at<uchar>(y, x) = (x + y) % 2 ? 255 : 0;
  check(checkerboard, "checkerboard");
  cv::Mat comb(30, 40, CV_8U, cv::Scalar(0));  // teeth hanging from a bar at the bottom
  for (int x = 1; x < 40; x += 2) comb(cv::Rect(x, 0, 1, 29)).setTo(255);
  check(comb, "comb");
  cv::Mat spiral(41, 41, CV_8U, cv::Scalar(255));  // one path winding inwards
  for (int i = 0; 2 * i < 20; ++i) {
    const int a = 2 * i, b = 40 - 2 * i;
    spiral.row(a).colRange(a, b + 1).setTo(0);
    spiral.col(b).rowRange(a, b + 1).setTo(0);
    spiral.row(b).colRange(a + 2, b + 1).setTo(0);
    spiral.col(a + 2).rowRange(a + 2, b + 1).setTo(0);
  }
  check(spiral, "spiral");
  cv::Mat row(1, 50, CV_8U), column(50, 1, CV_8U);
  rng.fill(row, cv::RNG::UNIFORM, 0, 2);
  rng.fill(column, cv::RNG::UNIFORM, 0, 2);
  check(row * 255, "one row");
  check(column * 255, "one column");
  check(cv::Mat(9, 9, CV_8U, cv::Scalar(255)), "all edges");
}

TEST(Segmenter, RejectsBadInput) {
  Camera cam = synth::default_camera(64, 48);
  EXPECT_THROW(segment(cv::Mat(48, 64, CV_16U, cv::Scalar(0)), cam), Error);      // all invalid
  EXPECT_THROW(segment(cv::Mat(48, 64, CV_8UC3, cv::Scalar(1)), cam), Error);     // colour
  EXPECT_THROW(segment(cv::Mat(40, 64, CV_16U, cv::Scalar(1000)), cam), Error);   // size mismatch
}

TEST(Temporal, AnyWindowLengthIsTheTwoPassBandMean) {
  // Windows shorter and longer than one kernel call takes (8 frames), against a plain two-pass loop:
  // the mean of the window's values within the band around the newest value, then within the band
  // around that mean.
  for (const int frames : {1, 3, 6, 8, 9, 13}) {
    Params::Smoothing p;
    p.temporal_frames = frames;
    TemporalSmoother t;
    cv::RNG rng(static_cast<uint64_t>(frames));
    std::vector<cv::Mat> window;
    cv::Mat out;
    for (int i = 0; i < frames + 2; ++i) {
      cv::Mat d(6, 7, CV_32F);
      rng.fill(d, cv::RNG::NORMAL, 1.0, 0.004);  // noise of about the band (10 mm at 1 m): some values fall out
      d.setTo(0, d > 1.008);                      // and some pixels have no measurement
      out = t.push(d, p);
      window.push_back(d);
      if (static_cast<int>(window.size()) > frames) window.erase(window.begin());
    }
    for (int y = 0; y < out.rows; ++y)
      for (int x = 0; x < out.cols; ++x) {
        const float newest = window.back().at<float>(y, x);
        float centre = newest;
        for (int pass = 0; pass < 2; ++pass) {
          const float limit = static_cast<float>(p.temporal_band) * centre * centre;
          float sum = 0, count = 0;
          for (const cv::Mat& f : window) {
            const float v = f.at<float>(y, x);
            if (v > 0 && v >= centre - limit && v <= centre + limit) sum += v, count += 1;
          }
          centre = newest > 0 ? sum / std::max(count, 1.f) : 0.f;
        }
        ASSERT_FLOAT_EQ(out.at<float>(y, x), centre) << frames << " frames, at (" << x << ", " << y << ")";
      }
  }
}

TEST(Temporal, AWindowOfCopiesAndAWindowOfAdoptedFramesAgree) {
  // push(const&) keeps a copy: the caller may reuse its image, as a camera loop filling one buffer does.
  // push(&&) keeps the frame's own buffer. Fed the same frames, both give the same output every frame.
  Params::Smoothing p;
  TemporalSmoother copies, adopted;
  cv::RNG rng(3);
  cv::Mat camera_buffer(9, 11, CV_32F);
  for (int i = 0; i < 10; ++i) {
    rng.fill(camera_buffer, cv::RNG::NORMAL, 1.0, 0.003);
    const cv::Mat from_copies = copies.push(camera_buffer, p);
    const cv::Mat from_adopted = adopted.push(camera_buffer.clone(), p);
    ASSERT_EQ(cv::countNonZero(from_copies != from_adopted), 0) << "frame " << i;
  }
}

TEST(Temporal, MovingBoxLeavesNoSmearAndStaticTableGetsQuieter) {
  // A box slides 4 cm per frame over a table; 1.5 mm of Gaussian depth noise on every frame.
  scenes::TestScene scene = scenes::box_on_plane();
  cv::RNG rng(7);
  TemporalSmoother t;
  Params::Smoothing p;
  cv::Mat out, truth_labels, truth_depth, raw;
  std::vector<cv::Mat> raw_frames, out_frames;
  for (int i = 0; i < 8; ++i) {
    scene.scene.shapes[1].pose.translation().x() = -0.16 + 0.04 * i;
    const auto truth = scene.render();
    cv::Mat noise(truth.depth.size(), CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.0015);
    raw = truth.depth + noise;
    raw.setTo(0, truth.depth == 0);
    out = t.push(raw, p);
    truth_labels = truth.labels;
    truth_depth = truth.depth;
    raw_frames.push_back(raw.clone());
    out_frames.push_back(out.clone());
  }
  // No smear: the box moves 4 cm a frame and is 10 cm tall, so a blend of old and new depth would be
  // centimetres off. Every pixel is within 12 mm of the newest true depth, and all but 0.5 % within
  // 3 noise sigmas, on the box and on the table it just uncovered.
  cv::Mat err;
  cv::absdiff(out, truth_depth, err);
  double worst = 0;
  cv::minMaxLoc(err, nullptr, &worst, nullptr, nullptr, truth_depth > 0);
  EXPECT_LT(worst, 0.012);
  EXPECT_LT(cv::countNonZero((err > 3 * 0.0015) & (truth_depth > 0)), 0.005 * cv::countNonZero(truth_depth));
  // Static table far from the box: the error against the true depth falls by about sqrt(6).
  const cv::Rect far_table(0, 200, 60, 40);
  auto noise = [&](const cv::Mat& f) {
    cv::Scalar m, sd;
    cv::meanStdDev(f(far_table) - truth_depth(far_table), m, sd);
    return sd[0];
  };
  EXPECT_LT(noise(out), 0.5 * noise(raw));  // 1/sqrt(6) = 0.41
}

TEST(Patches, UpdateAfterCutsEqualsAFreshExtraction) {
  // The table cut and the split at planes add edge pixels inside some patches; update_patches measures
  // only those again and must give exactly what extract_patches gives on the new edges: same ids, pixels
  // and statistics for every patch, the untouched ones included (they keep their old numbers otherwise).
  const scenes::TestScene scene = scenes::staircase();
  const auto truth = scene.render();
  const Params params;
  const NormalPlanes normals = compute_normals(truth.depth, scene.camera, 1, 5, 0.05f);
  cv::Mat edges = edge_mask(normal_edge_value(normals, 2), truth.depth, params.edges.theta, 0.05f);
  Patches before = extract_patches(edges, truth.depth, scene.camera, normals, params.patches, 20);
  ASSERT_GE(before.patches.size(), 4u);
  // Cut the largest patch (the table) and one other across with a line of edge pixels, as the cuts do.
  const auto largest = std::max_element(before.patches.begin(), before.patches.end(),
                                        [](const Patch& a, const Patch& b) { return a.pixels.size() < b.pixels.size(); });
  for (const Patch* cut : {&*largest, &before.patches[1]})
    for (int y = cut->bbox.y; y < cut->bbox.y + cut->bbox.height; ++y) {
      const int x = cut->bbox.x + cut->bbox.width / 2;
      if (before.labels.at<int>(y, x) == cut->id) edges.at<uchar>(y, x) = 255;
    }
  const Patches fresh = extract_patches(edges, truth.depth, scene.camera, normals, params.patches, 20);
  const Patches updated = update_patches(before, edges, truth.depth, scene.camera, normals, params.patches, 20);
  EXPECT_GT(fresh.patches.size(), before.patches.size());  // the cuts split patches
  EXPECT_EQ(cv::countNonZero(fresh.labels != updated.labels), 0);
  ASSERT_EQ(fresh.patches.size(), updated.patches.size());
  for (size_t k = 0; k < fresh.patches.size(); ++k) {
    const Patch &a = fresh.patches[k], &b = updated.patches[k];
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.pixels, b.pixels);
    EXPECT_EQ(a.centroid, b.centroid);
    EXPECT_EQ(a.mean_normal, b.mean_normal);
    EXPECT_EQ(a.spread_deg, b.spread_deg);
    EXPECT_EQ(a.histogram, b.histogram);
    EXPECT_EQ(a.occupied_bins, b.occupied_bins);
    EXPECT_EQ(a.curved, b.curved);
    EXPECT_EQ(a.bbox, b.bbox);
  }
  // A previous patch image that does not fit the edges is refused.
  EXPECT_THROW(update_patches(before, edges(cv::Rect(0, 0, 10, 10)).clone(), truth.depth, scene.camera, normals,
                              params.patches, 20), Error);
}

// Beyond the paper (normals.noise_floor): a D435-like active stereo camera (docs/SYNTH.md: correlated
// disparity noise, 4-5 mm RMS at 1.2 m) makes the default normals so noisy that most of a smooth table is
// edge pixels; the median edge value tells, and one wider smoothing brings the table back. A
// Kinect frame of the same scene keeps the paper's kernel (its median edge value is far above the floor).
TEST(Normals, ANoisySensorIsSmoothedOnceMore) {
  const Camera camera = synth::default_camera(640, 480);
  const synth::SynthFrame d435 = synth::synthesize("boxes", 11, 4, camera, synth::Sensor::RealSenseD435);
  const synth::SynthFrame kinect = synth::synthesize("boxes", 11, 4, camera, synth::Sensor::KinectV1);
  Params off;
  off.normals.noise_floor = 0;
  const auto edge_share = [](const Result& r) {  // of the pixels with depth
    int edges = 0, valid = 0;
    for (int i = 0; i < static_cast<int>(r.depth.total()); ++i)
      if (valid_depth(r.depth.ptr<float>()[i])) {
        ++valid;
        edges += r.edges.ptr<uchar>()[i] != 0;
      }
    return static_cast<double>(edges) / std::max(1, valid);
  };
  const Result noisy = segment(d435.sensor.depth, camera, off), smoothed = segment(d435.sensor.depth, camera);
  EXPECT_LT(median_edge_value(noisy.edge_value, noisy.depth), Params{}.normals.noise_floor);
  EXPECT_GT(edge_share(noisy), 0.8);     // the paper's kernel: 86 % of the scene is edges, the table in specks
  EXPECT_LT(edge_share(smoothed), 0.45);  // once more: 37 % (the Kinect's frame of the scene: 14 %)
  const Result plain = segment(kinect.sensor.depth, camera);
  EXPECT_GT(median_edge_value(plain.edge_value, plain.depth), Params{}.normals.noise_floor + 0.02);
  const Result plain_off = segment(kinect.sensor.depth, camera, off);
  EXPECT_EQ(cv::countNonZero(plain.core_patch_labels != plain_off.core_patch_labels), 0);  // untouched
}
