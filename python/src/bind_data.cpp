// Frames from files and dataset folders, label images out, and the metrics of `clutterseg eval`, so a
// user can score any method with the same code.
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>

#include "arrays.hpp"
#include "bindings.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/metrics.hpp"
#include "fields.hpp"

namespace clutterseg::python {

namespace {

// OpenCV reads BGR; Python users (matplotlib, PIL) expect RGB.
cv::Mat read_color_rgb(const fs::path& path) {
  if (!fs::exists(path)) throw Error(path.string() + ": no such file");
  cv::Mat bgr = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (bgr.empty()) throw Error(path.string() + ": cannot be read as an image");
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return rgb;
}

// One frame of a dataset folder, checked the way `clutterseg segment` and `eval` check it: the
// intrinsics must fit the depth image, a label image of another size is an error, a colour image of
// another size is left out (it is only decoration).
py::tuple load_frame(const fs::path& depth_path, const std::optional<fs::path>& color_path,
                     const std::optional<fs::path>& label_path, const Camera& camera) {
  cv::Mat depth, color, label;
  {
    py::gil_scoped_release release;
    depth = read_depth_png(depth_path);
    check_camera(camera, depth.cols, depth.rows, depth_path.string());
    if (color_path) {
      color = read_color_rgb(*color_path);
      if (color.size() != depth.size()) color.release();
    }
    if (label_path) {
      label = read_label_png(*label_path);
      if (label.size() != depth.size()) throw Error(label_path->string() + ": label image size differs from the depth image");
    }
  }
  const auto or_none = [](const cv::Mat& m) { return m.empty() ? py::object(py::none()) : py::object(to_numpy(m)); };
  return py::make_tuple(to_numpy(depth), or_none(color), or_none(label));
}

void bind_io(py::module_& m) {
  m.def(
      "read_depth", [](const fs::path& path) { return to_numpy(read_depth_png(path)); }, py::arg("path"),
      "Reads a 16-bit single-channel depth PNG as uint16 (H, W) (steps of camera.depth_unit_m, 0 = none).\n"
      "Raises clutterseg.Error naming the file for anything else.");
  m.def(
      "read_labels", [](const fs::path& path) { return to_numpy(read_label_png(path)); }, py::arg("path"),
      "Reads an 8- or 16-bit label PNG (0 = none) as int32 (H, W).");
  m.def(
      "read_color", [](const fs::path& path) { return to_numpy(read_color_rgb(path)); }, py::arg("path"),
      "Reads a colour image as uint8 (H, W, 3) RGB.");
  m.def(
      "write_labels",
      [](const fs::path& path, const py::object& labels) {
        const cv::Mat ids = label_view(labels, "labels");
        py::gil_scoped_release release;
        write_png_atomic(path, labels_to_u16(ids));
      },
      py::arg("path"), py::arg("labels"),
      "Writes a label image (integer ids 0..65535, 0 = none) as a 16-bit PNG, atomically: the form\n"
      "`clutterseg eval DATASET --pred DIR` reads (DIR/NAME.png).");
  m.def("_list_dataset",
        [](const fs::path& dataset) {
          py::list frames;
          for (const FrameFiles& f : list_dataset(dataset))
            frames.append(py::make_tuple(f.name, f.depth, f.color, f.label));
          return frames;
        },
        py::arg("dataset"), "(name, depth, color or None, label or None) paths of a dataset's frames, in name order");
  m.def("_load_frame", &load_frame, py::arg("depth"), py::arg("color"), py::arg("label"), py::arg("camera"),
        "(depth uint16, color RGB or None, label int32 or None) of one frame, checked against the camera");
}

void bind_metrics(py::module_& m) {
  py::class_<FrameScores> scores(
      m, "FrameScores",
      "Scores of one image as fractions in [0, 1] (SPEC Sec. 4), as `clutterseg eval` computes them.\n"
      "NaN when undefined: every score of an image without ground-truth objects.");
  Fields<FrameScores>(scores)
      .add("gt_objects", [](const FrameScores& s) { return s.gt_objects; }, "ids != 0 in the ground truth")
      .add("pred_objects", [](const FrameScores& s) { return s.pred_objects; }, "ids != 0 in the prediction")
      .add("matched", [](const FrameScores& s) { return s.matched; }, "Hungarian pairs with overlap (F > 0)")
      .add("tp", [](const FrameScores& s) { return s.tp; }, "paper: mean share of each ground-truth object covered by its best segment")
      .add("fp", [](const FrameScores& s) { return s.fp; }, "paper: mean share of that segment lying outside the object")
      .add("fn", [](const FrameScores& s) { return s.fn; }, "paper: 1 - tp")
      .add("overlap_p", [](const FrameScores& s) { return s.overlap_p; }, "UOIS Overlap precision")
      .add("overlap_r", [](const FrameScores& s) { return s.overlap_r; }, "UOIS Overlap recall")
      .add("overlap_f", [](const FrameScores& s) { return s.overlap_f; }, "UOIS Overlap F-measure")
      .add("boundary_p", [](const FrameScores& s) { return s.boundary_p; }, "UOIS Boundary precision")
      .add("boundary_r", [](const FrameScores& s) { return s.boundary_r; }, "UOIS Boundary recall")
      .add("boundary_f", [](const FrameScores& s) { return s.boundary_f; }, "UOIS Boundary F-measure")
      .add("detected_75", [](const FrameScores& s) { return s.detected_75; }, "UOIS %>=75: share of objects matched with F > 0.75")
      .finish();
  scores.def_property_readonly("scored", &FrameScores::scored, "True when the ground truth holds objects");

  py::tuple names(kScoreNames.size());
  for (size_t k = 0; k < kScoreNames.size(); ++k) names[k] = kScoreNames[k];
  m.attr("SCORE_NAMES") = names;

  m.def(
      "score_frame",
      [](const py::object& ground_truth, const py::object& prediction) {
        const cv::Mat truth = label_view(ground_truth, "ground_truth"), pred = label_view(prediction, "prediction");
        if (truth.size() != pred.size())
          throw py::value_error("prediction: size " + std::to_string(pred.cols) + "x" + std::to_string(pred.rows) +
                                " differs from the ground truth's " + std::to_string(truth.cols) + "x" +
                                std::to_string(truth.rows));
        py::gil_scoped_release release;
        return score_frame(truth, pred);
      },
      py::arg("ground_truth"), py::arg("prediction"),
      "score_frame(ground_truth, prediction) -> FrameScores\n\n"
      "Both metric families of one image: the paper's tp/fp/fn and the UOIS Overlap and Boundary P/R/F.\n"
      "  ground_truth, prediction: 2-D integer label images of one size (int32, uint16, uint8 read in place;\n"
      "  other integer dtypes converted), 0 = not an object on both sides. Ids need not match: the\n"
      "  prediction's segments are matched to the ground-truth objects.");
  m.def("boundary_tolerance_px", [](int width, int height) { return boundary_tolerance_px(cv::Size(width, height)); },
        py::arg("width"), py::arg("height"),
        "Boundary tolerance of the UOIS Boundary scores: ceil(0.003 * image diagonal) [px] (3 at 640x480).");
  m.def(
      "object_boundaries", [](const py::object& labels) { return to_numpy(object_boundaries(label_view(labels, "labels"))); },
      py::arg("labels"), "uint8 (H, W): 255 where a pixel's 4-neighbour carries another id (label 0 is never boundary).");
  m.def(
      "mean_std",
      [](const std::vector<double>& values) {
        const MeanStd s = mean_std(values);
        return py::make_tuple(s.mean, s.std, s.count);
      },
      py::arg("values"), "(mean, population std, count) of the finite values, NaN ignored (as eval averages).");
}

}  // namespace

void bind_data(py::module_& m) {
  bind_io(m);
  bind_metrics(m);
}

}  // namespace clutterseg::python
