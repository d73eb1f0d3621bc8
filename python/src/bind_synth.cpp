// clutterseg.synth: the synthetic table-top scenes of `clutterseg synth`, with exact labels, so a user
// can test a method on scenes whose answer is known.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <opencv2/imgproc.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "clutterseg/synth/dataset.hpp"

namespace clutterseg::python {

namespace {

struct PySynthFrame {
  synth::SynthFrame frame;
  Camera camera;
  std::string preset;
  std::uint64_t seed = 0;
  int index = 0;
};

// A bad preset or sensor name is a bad argument: ValueError with the core's message.
synth::Sensor checked_arguments(const std::string& preset, const std::string& sensor) {
  try {
    synth::preset_info(preset);
    return synth::parse_sensor(sensor);
  } catch (const Error& e) {
    throw py::value_error(e.what());
  }
}

Camera camera_or_default(const std::optional<Camera>& camera) {
  return camera ? *camera : synth::default_camera();
}

py::dict object_dict(const synth::ObjectInfo& o) {
  py::dict d;
  d["id"] = o.id;
  d["type"] = o.type;
  d["size"] = o.size;
  d["pose"] = Eigen::Matrix4d(o.pose.matrix());
  return d;
}

}  // namespace

void bind_synth(py::module_& root) {
  py::module_ m = root.def_submodule(
      "synth", "Synthetic table-top scenes with exact labels and a depth-sensor model (`clutterseg synth`).");

  m.def(
      "presets",
      [] {
        py::list list;
        for (const auto& p : synth::presets()) {
          py::dict d;
          d["name"] = p.name;
          d["description"] = p.description;
          d["min_objects"] = p.min_objects;
          d["max_objects"] = p.max_objects;
          list.append(d);
        }
        return list;
      },
      "The scene presets as dicts {name, description, min_objects, max_objects} (`clutterseg synth --list`).");
  m.def("sensors", &synth::sensor_names, "Names of the sensor models: ideal, kinect-v1, realsense-d435.");
  m.def("default_camera", &synth::default_camera, py::arg("width") = 640, py::arg("height") = 480,
        "A Kinect-like camera: fx = fy = 525 * width / 640 [px], principal point at the image centre.");

  py::class_<PySynthFrame>(m, "SynthFrame", "One synthetic frame: what the sensor reports, and the exact answer.")
      .def_property_readonly("depth_mm", [](const PySynthFrame& f) { return to_numpy(f.frame.sensor.depth_mm); },
                             "uint16 (H, W): depth as a sensor delivers it [mm], 0 = none (give it to Segmenter.segment)")
      .def_property_readonly("depth", [](const PySynthFrame& f) { return to_numpy(f.frame.sensor.depth); },
                             "float32 (H, W): reported depth before rounding to mm [m], 0 = none")
      .def_property_readonly("labels", [](const PySynthFrame& f) { return to_numpy(f.frame.sensor.labels); },
                             "int32 (H, W): exact object id per pixel, 0 = table and background (the ground truth)")
      .def_property_readonly("color",
                             [](const PySynthFrame& f) {
                               cv::Mat rgb;
                               cv::cvtColor(f.frame.sensor.color, rgb, cv::COLOR_BGR2RGB);
                               return to_numpy(rgb);
                             },
                             "uint8 (H, W, 3) RGB: Lambertian shading of the exact geometry")
      .def_property_readonly("true_depth", [](const PySynthFrame& f) { return to_numpy(f.frame.sensor.true_depth); },
                             "float32 (H, W): exact camera z [m], 0 = nothing hit")
      .def_property_readonly("shadow", [](const PySynthFrame& f) { return to_numpy(f.frame.sensor.shadow); },
                             "uint8 (H, W): 255 where the projector (or second imager) cannot see the surface")
      .def_readonly("camera", &PySynthFrame::camera, "the Camera it was rendered with")
      .def_property_readonly("family", [](const PySynthFrame& f) { return f.frame.scene.family; },
                             "what eval groups by (the preset name)")
      .def_property_readonly(
          "objects",
          [](const PySynthFrame& f) {
            py::list list;
            for (const auto& o : f.frame.scene.objects) list.append(object_dict(o));
            return list;
          },
          "list of dicts {id, type, size [m] (3,), pose 4x4 object -> world}; ids as in labels")
      .def_property_readonly("world_to_camera",
                             [](const PySynthFrame& f) { return Eigen::Matrix4d(f.frame.scene.world_to_camera.matrix()); },
                             "4x4 float64: world (table top z = 0, z up) -> camera")
      .def("__repr__", [](const PySynthFrame& f) {
        return "SynthFrame(preset='" + f.preset + "', seed=" + std::to_string(f.seed) + ", frame=" +
               std::to_string(f.index) + ", objects=" + std::to_string(f.frame.scene.objects.size()) + ")";
      });

  m.def(
      "synthesize",
      [](const std::string& preset, std::uint64_t seed, int frame, const std::optional<Camera>& camera,
         const std::string& sensor) {
        PySynthFrame out;
        out.camera = camera_or_default(camera);
        out.preset = preset;
        out.seed = seed;
        out.index = frame;
        const synth::Sensor model = checked_arguments(preset, sensor);
        py::gil_scoped_release release;
        out.frame = synth::synthesize(preset, seed, frame, out.camera, model);
        return out;
      },
      py::arg("preset"), py::arg("seed") = 0, py::arg("frame") = 0, py::arg("camera") = py::none(),
      py::arg("sensor") = "kinect-v1",
      "synthesize(preset, seed=0, frame=0, camera=None, sensor='kinect-v1') -> SynthFrame\n\n"
      "Frame `frame` of a preset (see presets()); a function of its arguments only, the same as frame\n"
      "`frame` of `clutterseg synth --preset PRESET --seed SEED`.\n"
      "  camera: Camera (width and height set); None = default_camera() (640x480 Kinect-like)\n"
      "  sensor: 'ideal', 'kinect-v1' or 'realsense-d435' (noise, quantisation, shadows, dropouts)");
  m.def(
      "write_dataset",
      [](const std::filesystem::path& out, const std::string& preset, int frames, std::uint64_t seed,
         const std::optional<Camera>& camera, const std::string& sensor, int threads, bool overwrite) {
        synth::DatasetOptions o;
        o.preset = preset;
        o.frames = frames;
        o.seed = seed;
        o.out = out;
        o.camera = camera_or_default(camera);
        o.sensor = checked_arguments(preset, sensor);
        o.threads = threads;
        o.overwrite = overwrite;
        py::gil_scoped_release release;
        synth::write_dataset(o);
      },
      py::arg("out"), py::arg("preset"), py::arg("frames") = 10, py::arg("seed") = 0, py::arg("camera") = py::none(),
      py::arg("sensor") = "kinect-v1", py::arg("threads") = 0, py::arg("overwrite") = false,
      "Writes a dataset folder (camera.json, depth/, label/, color/, scenes.json) as `clutterseg synth` does;\n"
      "read it with clutterseg.Dataset. threads: 0 = all cores (the bytes do not depend on it).");
}

}  // namespace clutterseg::python
