// Camera, Segmenter and Result: depth in as a view on the caller's array, images out as views on the
// core's cv::Mat buffers (python/src/arrays.hpp), the GIL released while a frame is segmented.
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <ctime>
#include <cstdint>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>

#include "arrays.hpp"
#include "bindings.hpp"
#include "clutterseg/config.hpp"
#include "clutterseg/io.hpp"
#include "clutterseg/objects.hpp"
#include "clutterseg/pipeline.hpp"
#include "clutterseg/segmenter.hpp"
#include "fields.hpp"

namespace clutterseg::python {

namespace {

// One segmented frame. Images are handed out as views on these buffers; the lists of objects,
// patches and links are built on first access and kept, so `result.objects[i]` in a loop is cheap.
struct PyResult {
  Result r;
  std::uintptr_t input_address = 0;  // where the depth pixels the core read were (tests check: no copy)
  // Start and end of the C++ Segmenter::segment call on the monotonic clock [s], the clock of Python's
  // time.perf_counter(): tests see what ran meanwhile, the overhead measurement what was outside it.
  double core_start_s = 0, core_end_s = 0;
  double core_cpu_start_s = 0, core_cpu_end_s = 0;  // CPU time of the calling thread, time.thread_time()'s clock
  py::object objects, patches, graph, normals, objects_only, hidden_objects;
  bool tracked = false;  // ids are track ids (Params::Tracking): the objects-only view keeps them
};

double clock_seconds(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The caller's depth array as a cv::Mat view (no copy), and `camera` checked against it; a camera made
// without a size (Camera(fx, fy, cx, cy)) takes the image's. ValueError for a camera that does not fit.
cv::Mat depth_view(const py::object& depth_array, Camera& camera) {
  const cv::Mat depth = view_2d(depth_array, {CV_16U, CV_32F}, "depth");
  if (camera.width == 0 && camera.height == 0) {
    camera.width = depth.cols;
    camera.height = depth.rows;
  }
  try {
    check_camera(camera, depth.cols, depth.rows, "camera");
  } catch (const Error& e) {
    throw py::value_error(e.what());
  }
  return depth;
}

// A Segmenter shared by Python threads: calls on one instance take turns (the temporal window is one
// stream); different instances run in parallel, the GIL released.
class PySegmenter {
 public:
  explicit PySegmenter(const std::string& params_json) {
    // Every parameter problem the core finds (unknown name, wrong type, out of range) is a ValueError.
    try {
      segmenter_ = std::make_unique<Segmenter>(params_from_json(params_json, "clutterseg.Segmenter params"));
    } catch (const Error& e) {
      throw py::value_error(e.what());
    }
  }

  std::shared_ptr<PyResult> segment(const py::object& depth_array, Camera camera) {
    const cv::Mat depth = depth_view(depth_array, camera);
    auto out = std::make_shared<PyResult>();
    out->input_address = reinterpret_cast<std::uintptr_t>(depth.data);
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      out->core_cpu_start_s = clock_seconds(CLOCK_THREAD_CPUTIME_ID);
      out->core_start_s = clock_seconds(CLOCK_MONOTONIC);
      out->r = segmenter_->segment(depth, camera);
      out->tracked = segmenter_->params().tracking.enabled;
      out->core_end_s = clock_seconds(CLOCK_MONOTONIC);
      out->core_cpu_end_s = clock_seconds(CLOCK_THREAD_CPUTIME_ID);
    }
    return out;
  }

  void reset() {
    const std::lock_guard<std::mutex> lock(mutex_);
    segmenter_->reset();
  }

  std::string params_json() const { return params_to_json(segmenter_->params()); }

 private:
  std::unique_ptr<Segmenter> segmenter_;
  std::mutex mutex_;
};

// A Pipeline (frames of one stream on several cores, Results in order): push keeps the depth array
// alive until its Result is popped, because the core reads it in place. Meant for one Python thread (a
// stream has one order); the GIL is released while it waits (push when `capacity` frames are in
// flight, pop until the oldest is done), so other Python threads run meanwhile.
class PyPipeline {
 public:
  explicit PyPipeline(const std::string& params_json) {
    try {
      params_ = params_from_json(params_json, "clutterseg.Pipeline params");
      pipeline_ = std::make_unique<Pipeline>(params_);
    } catch (const Error& e) {
      throw py::value_error(e.what());
    }
  }

  // The frames in flight are finished before their arrays are let go (the workers read them).
  ~PyPipeline() {
    py::gil_scoped_release release;
    pipeline_.reset();
  }

  void push(const py::object& depth_array, Camera camera) {
    const cv::Mat depth = depth_view(depth_array, camera);
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      pipeline_->push(depth, camera);
    }
    arrays_.push_back({depth_array, reinterpret_cast<std::uintptr_t>(depth.data)});
  }

  std::shared_ptr<PyResult> pop() {
    if (arrays_.empty()) throw py::value_error("clutterseg.Pipeline.pop: no frame in flight (push one first)");
    auto out = std::make_shared<PyResult>();
    out->input_address = arrays_.front().second;
    std::exception_ptr error;
    {
      py::gil_scoped_release release;
      const std::lock_guard<std::mutex> lock(mutex_);
      try {
        out->r = pipeline_->pop();
      } catch (...) {
        error = std::current_exception();
      }
    }
    arrays_.pop_front();  // the frame is done with, whatever it threw
    if (error) std::rethrow_exception(error);
    out->tracked = params_.tracking.enabled;
    return out;
  }

  void reset() {
    const std::lock_guard<std::mutex> lock(mutex_);
    pipeline_->reset();
  }

  int in_flight() const { return static_cast<int>(arrays_.size()); }
  int capacity() const { return pipeline_->capacity(); }
  int workers() const { return pipeline_->workers(); }

 private:
  std::unique_ptr<Pipeline> pipeline_;
  Params params_;
  std::deque<std::pair<py::object, std::uintptr_t>> arrays_;  // pushed, not yet popped; touched with the GIL held
  std::mutex mutex_;
};

// The core's vectors are by value; Python gets copies as float32 / float64 NumPy arrays.
template <typename T>
py::list to_list(const std::vector<T>& items) {
  py::list list;
  for (const auto& item : items) list.append(py::cast(item));
  return list;
}

py::object cached(py::object& slot, const std::function<py::object()>& make) {
  if (!slot) slot = make();
  return slot;
}

std::string camera_repr(const Camera& c) {
  return "Camera(fx=" + py::repr(py::float_(c.fx)).cast<std::string>() +
         ", fy=" + py::repr(py::float_(c.fy)).cast<std::string>() +
         ", cx=" + py::repr(py::float_(c.cx)).cast<std::string>() +
         ", cy=" + py::repr(py::float_(c.cy)).cast<std::string>() + ", width=" + std::to_string(c.width) +
         ", height=" + std::to_string(c.height) + ", depth_unit_m=" + py::repr(py::float_(c.depth_unit_m)).cast<std::string>() + ")";
}

void bind_camera(py::module_& m) {
  py::class_<Camera>(m, "Camera",
                     "Pinhole intrinsics of a depth image, and the unit of integer depth.\n\n"
                     "Camera(fx, fy, cx, cy, width=0, height=0, depth_unit_m=0.001)\n"
                     "  fx, fy: focal lengths [px]; cx, cy: principal point [px] (pixel centres at integers)\n"
                     "  width, height: image size [px]; 0, 0 takes the size of the depth image given to segment()\n"
                     "  depth_unit_m: metres per step of uint16 depth (0.001 = millimetres)\n"
                     "  camera_to_robot: 4x4 pose (float64) applied to object centroids and boxes; identity = camera frame")
      .def(py::init([](double fx, double fy, double cx, double cy, int width, int height, double depth_unit_m) {
             Camera c;
             c.fx = fx;
             c.fy = fy;
             c.cx = cx;
             c.cy = cy;
             c.width = width;
             c.height = height;
             c.depth_unit_m = depth_unit_m;
             return c;
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::arg("width") = 0, py::arg("height") = 0,
           py::arg("depth_unit_m") = 0.001)
      .def_static(
          "from_json", [](const fs::path& path) { return read_camera_json(path); }, py::arg("path"),
          "Reads camera.json {fx, fy, cx, cy, width, height, depth_unit_m} (the dataset layout's file).\n"
          "Raises clutterseg.Error naming the file when it cannot be read or a value is missing or not positive.")
      .def(
          "to_json", [](const Camera& c, const fs::path& path) { write_camera_json(path, c); }, py::arg("path"),
          "Writes camera.json (atomically).")
      .def_readwrite("fx", &Camera::fx, "focal length x [px]")
      .def_readwrite("fy", &Camera::fy, "focal length y [px]")
      .def_readwrite("cx", &Camera::cx, "principal point x [px]")
      .def_readwrite("cy", &Camera::cy, "principal point y [px]")
      .def_readwrite("width", &Camera::width, "image width [px] (0: the depth image's)")
      .def_readwrite("height", &Camera::height, "image height [px] (0: the depth image's)")
      .def_readwrite("depth_unit_m", &Camera::depth_unit_m, "metres per step of uint16 depth")
      .def_readwrite("camera_to_robot", &Camera::camera_to_robot,
                     "4x4 float64 pose camera -> robot, applied to object centroids and boxes")
      .def("__repr__", camera_repr);
}

void bind_parts(py::module_& m) {
  py::class_<OrientedBox> box(m, "OrientedBox", "A PCA-oriented 3D box around an object's points.");
  Fields<OrientedBox>(box)
      .add("center", [](const OrientedBox& b) { return b.center; }, "centre [m], float32 (3,)")
      .add("axes", [](const OrientedBox& b) { return b.axes; }, "float32 (3, 3): columns are unit axes, largest extent first")
      .add("extents", [](const OrientedBox& b) { return b.extents; }, "full side lengths along the axes [m], float32 (3,)")
      .finish();

  py::class_<Plane> plane(m, "Plane", "A plane normal . x + offset = 0 in the camera frame (the support plane).");
  Fields<Plane>(plane)
      .add("normal", [](const Plane& p) { return p.normal; }, "unit normal facing the camera, float32 (3,)")
      .add("offset", [](const Plane& p) { return p.offset; }, "offset [m]: normal . x + offset = 0")
      .finish();
  plane.def(
      "distance", [](const Plane& p, const Eigen::Vector3f& x) { return p.distance(x); }, py::arg("point"),
      "Signed distance [m] of a camera-frame point (positive: on the camera's side).");

  // Every field of clutterseg::Object, one line each (tracking fields are added here the same way).
  py::class_<Object> object(m, "Object", "One object hypothesis of a frame.");
  Fields<Object>(object)
      .add("id", [](const Object& o) { return o.id; },
           "label in Result.object_labels: kept from frame to frame of a stream (tracking), 1..M without tracking")
      .add("pixel_count", [](const Object& o) { return o.pixel_count; }, "pixels carrying this id")
      .add("centroid", [](const Object& o) { return o.centroid; },
           "mean of its 3D points [m], float32 (3,); robot frame if Camera.camera_to_robot is set, else camera frame")
      .add("box", [](const Object& o) { return o.box; }, "oriented bounding box (OrientedBox), same frame as centroid")
      .add("patches",
           [](const Object& o) {
             std::vector<int> ids;
             for (int p : o.patches) ids.push_back(p + 1);
             return ids;
           },
           "ids of its surface patches (labels in Result.patch_labels, 1..N)")
      .add("cut_cost", [](const Object& o) { return o.cut_cost; },
           "confidence: cost of the cheapest graph cut that would split it (higher = more firmly one object); inf for one patch")
      .add("support", [](const Object& o) { return o.support; }, "True for the table the objects stand on")
      .add("background", [](const Object& o) { return o.background; }, "True for walls and far surfaces")
      .add("age", [](const Object& o) { return o.age; }, "frames since it was first seen, this one included (1 = new)")
      .add("frames_missed", [](const Object& o) { return o.frames_missed; },
           "frames it was unseen just before this one (0 = seen in the previous frame)")
      .add("split_from", [](const Object& o) { return o.split_from; }, "id of the object it split off from, 0 = none")
      .add("merged_with", [](const Object& o) { return o.merged_with; },
           "ids of remembered objects merged into it (see Result.hidden_objects)")
      .finish();
  object.def_property_readonly(
      "confidence", [](const Object& o) { return o.cut_cost; }, "the same as cut_cost");

  py::class_<HiddenObject> hidden(m, "HiddenObject",
                                  "A tracked object not seen in this frame: occluded, gone for a while, or merged into another.");
  Fields<HiddenObject>(hidden)
      .add("id", [](const HiddenObject& h) { return h.id; }, "its id (it gets it back when it is seen again)")
      .add("age", [](const HiddenObject& h) { return h.age; }, "frames since it was first seen")
      .add("frames_since_seen", [](const HiddenObject& h) { return h.frames_since_seen; }, "frames since it was last seen (>= 1)")
      .add("merged_into", [](const HiddenObject& h) { return h.merged_into; }, "id of the object it merged with, 0 = none")
      .add("centroid", [](const HiddenObject& h) { return h.centroid; }, "where it was last seen [m], float32 (3,)")
      .add("box", [](const HiddenObject& h) { return h.box; }, "its OrientedBox when last seen")
      .finish();

  py::class_<Patch> patch(m, "Patch", "A surface patch (paper stage c): statistics over its core pixels.");
  Fields<Patch>(patch)
      .add("id", [](const Patch& p) { return p.id; }, "label in Result.core_patch_labels and Result.patch_labels (1..N)")
      .add("pixel_count", [](const Patch& p) { return p.pixels.size(); }, "core pixels (before edge pixels were assigned)")
      .add("centroid", [](const Patch& p) { return p.centroid; }, "mean of its points, camera frame [m], float32 (3,)")
      .add("mean_normal", [](const Patch& p) { return p.mean_normal; }, "unit mean normal facing the camera, float32 (3,)")
      .add("spread_deg", [](const Patch& p) { return p.spread_deg; }, "mean angle of its pixel normals to the mean normal [deg]")
      .add("histogram",
           [](const Patch& p) {
             const auto bins = static_cast<py::ssize_t>(std::lround(std::sqrt(static_cast<double>(p.histogram.size()))));
             py::array_t<float> h({bins, bins});
             std::copy(p.histogram.begin(), p.histogram.end(), h.mutable_data());
             return h;
           },
           "shares of its pixel normals per (y, x) bin of the normal's y and x, float32 (bins, bins), sums to 1")
      .add("occupied_bins", [](const Patch& p) { return p.occupied_bins; }, "histogram bins above patches.occupied_share")
      .add("curved", [](const Patch& p) { return p.curved; }, "True when occupied_bins >= patches.flat_max_bins")
      .add("bbox", [](const Patch& p) { return py::make_tuple(p.bbox.x, p.bbox.y, p.bbox.width, p.bbox.height); },
           "image bounding box (x, y, width, height) [px]")
      .finish();
  patch.def_property_readonly(
      "pixels",
      [](const Patch& p) {
        py::array_t<std::int32_t> a(static_cast<py::ssize_t>(p.pixels.size()));
        std::copy(p.pixels.begin(), p.pixels.end(), a.mutable_data());
        return a;
      },
      "linear indices y * width + x of its core pixels, int32 (a copy)");

  py::class_<GraphEdge> edge(m, "GraphEdge", "A link of the patch graph (paper stage i).");
  Fields<GraphEdge>(edge)
      .add("a", [](const GraphEdge& e) { return e.a + 1; }, "patch id (1..N), a < b")
      .add("b", [](const GraphEdge& e) { return e.b + 1; }, "patch id (1..N)")
      .add("cue", [](const GraphEdge& e) { return std::string(to_string(e.cue)); },
           "why they are linked: adjacent, coplanar, curvature-open or curvature-occluded")
      .add("weight", [](const GraphEdge& e) { return e.weight; }, "symmetrised 1/deg weight")
      .finish();
}

void bind_result(py::module_& m) {
  py::class_<PyResult, std::shared_ptr<PyResult>>(
      m, "Result",
      "One segmented frame. Image attributes are NumPy arrays on the core's own buffers (no copy); they stay\n"
      "valid after the Result is gone. Lists (objects, patches, graph) are built on first access.")
      .def_property_readonly(
          "object_labels", [](const PyResult& p) { return to_numpy(p.r.object_labels); },
          "int32 (H, W): object id 1..M per pixel, 0 = none (table and background included; see objects_only_labels)")
      .def_property_readonly(
          "objects_only_labels",
          [](PyResult& p) {
            return cached(p.objects_only, [&] { return to_numpy(objects_only(p.r.object_labels, p.r.objects, p.tracked)); });
          },
          "int32 (H, W): object_labels with the support plane and background set to 0; the rest keep their ids\n"
          "when tracking (tracking.enabled), else are renumbered 1..K (what `clutterseg segment --objects-only`\n"
          "writes and `clutterseg eval` scores)")
      .def_property_readonly(
          "patch_labels", [](const PyResult& p) { return to_numpy(p.r.patch_labels); },
          "int32 (H, W): surface patch id 1..N per pixel after edge pixels were assigned, 0 = none")
      .def_property_readonly(
          "core_patch_labels", [](const PyResult& p) { return to_numpy(p.r.core_patch_labels); },
          "int32 (H, W): surface patches before edge pixels were assigned, 0 = edge or no depth\n"
          "(what `clutterseg segment` writes to patch/NAME.png)")
      .def_property_readonly(
          "depth", [](const PyResult& p) { return to_numpy(p.r.depth); },
          "float32 (H, W): depth after smoothing [m], 0 = no measurement")
      .def_property_readonly(
          "points", [](const PyResult& p) { return to_numpy(p.r.points); },
          "float32 (H, W, 3): camera-frame points [m] (x right, y down, z forward); (0, 0, 0) = no measurement")
      .def_property_readonly(
          "normals",
          [](PyResult& p) {
            return cached(p.normals, [&] {
              cv::Mat merged;
              cv::merge(p.r.normals.data(), p.r.normals.size(), merged);
              return to_numpy(merged);
            });
          },
          "float32 (H, W, 3): unit normals facing the camera, (0, 0, 0) = none. The core keeps the normals as\n"
          "three planes; this interleaved array is the one copy a Result makes (built on first access).\n"
          "normal_planes gives the planes without a copy.")
      .def_property_readonly(
          "normal_planes",
          [](const PyResult& p) {
            return py::make_tuple(to_numpy(p.r.normals[0]), to_numpy(p.r.normals[1]), to_numpy(p.r.normals[2]));
          },
          "(nx, ny, nz): the normals' x, y and z as three float32 (H, W) arrays, no copy")
      .def_property_readonly(
          "edge_value", [](const PyResult& p) { return to_numpy(p.r.edge_value); },
          "float32 (H, W): mean |n . n_q| over 8 neighbours (paper stage b); low = edge")
      .def_property_readonly(
          "edges", [](const PyResult& p) { return to_numpy(p.r.edges); }, "uint8 (H, W): 255 = edge pixel")
      .def_property_readonly(
          "objects", [](PyResult& p) { return cached(p.objects, [&] { return to_list(p.r.objects); }); },
          "list of Object, sorted by id (objects[i].id == i + 1 without tracking)")
      .def_property_readonly(
          "hidden_objects",
          [](PyResult& p) { return cached(p.hidden_objects, [&] { return to_list(p.r.hidden_objects); }); },
          "list of HiddenObject: tracked objects not seen in this frame, sorted by id")
      .def_property_readonly(
          "patches", [](PyResult& p) { return cached(p.patches, [&] { return to_list(p.r.patches); }); },
          "list of Patch, patches[i].id == i + 1")
      .def_property_readonly(
          "graph", [](PyResult& p) { return cached(p.graph, [&] { return to_list(p.r.graph); }); },
          "list of GraphEdge: the weighted patch graph with the cue of each link")
      .def_property_readonly(
          "support_plane",
          [](const PyResult& p) { return p.r.support_plane ? py::cast(*p.r.support_plane) : py::none(); },
          "Plane of the table in the camera frame, or None when no table was found")
      .def_property_readonly(
          "timings_ms",
          [](const PyResult& p) {
            py::dict d;
            for (const auto& [stage, ms] : p.r.timings_ms) d[stage.c_str()] = ms;
            return d;
          },
          "dict stage -> wall time [ms], in pipeline order; the last entry is 'total'")
      .def_property_readonly("_input_address", [](const PyResult& p) { return p.input_address; },
                             "address of the depth pixels the core read (tests: no copy was made)")
      .def_property_readonly("_core_window", [](const PyResult& p) { return py::make_tuple(p.core_start_s, p.core_end_s); },
                             "(start, end) of the C++ Segmenter::segment call in time.perf_counter() seconds")
      .def_property_readonly("_core_cpu_window",
                             [](const PyResult& p) { return py::make_tuple(p.core_cpu_start_s, p.core_cpu_end_s); },
                             "(start, end) of the C++ call in time.thread_time() seconds (the calling thread's CPU time)")
      .def("__repr__", [](const PyResult& p) {
        return "Result(" + std::to_string(p.r.object_labels.cols) + "x" + std::to_string(p.r.object_labels.rows) +
               ", objects=" + std::to_string(p.r.objects.size()) + ", patches=" + std::to_string(p.r.patches.size()) +
               ")";
      });
}

}  // namespace

void bind_segmenter(py::module_& m) {
  bind_camera(m);
  bind_parts(m);
  bind_result(m);

  m.def(
      "_read_params",
      [](const std::string& text) {
        try {
          return params_to_json(params_from_json(text, "clutterseg.Segmenter params"));
        } catch (const Error& e) {
          throw py::value_error(e.what());
        }
      },
      py::arg("params_json"), "every parameter as JSON text, after the core read `params_json` (ValueError if it cannot)");

  py::class_<PySegmenter>(m, "Segmenter", "The C++ segmenter; use clutterseg.Segmenter, which takes dicts and keywords.")
      .def(py::init<const std::string&>(), py::arg("params_json"),
           "params_json: parameters as JSON text (the form of `clutterseg --dump-config`)")
      .def("segment", &PySegmenter::segment, py::arg("depth"), py::arg("camera"),
           "segment(depth, camera) -> Result\n\n"
           "Segments one depth frame of a stream; the temporal window advances (reset() starts a new stream).\n"
           "  depth: 2-D NumPy array (height x width), read in place without a copy:\n"
           "         uint16 in steps of camera.depth_unit_m (millimetres by default), 0 = no measurement, or\n"
           "         float32 in metres, 0 or NaN = no measurement.\n"
           "         Rows may be padded (a cropped view works); pixels within a row must be adjacent.\n"
           "  camera: clutterseg.Camera with the intrinsics of this image [px].\n"
           "Raises TypeError for another dtype, ValueError for another shape, an empty or non-contiguous array\n"
           "or intrinsics that do not fit the image, clutterseg.Error for a frame without any valid depth.\n"
           "The GIL is released while the frame is segmented: Segmenters in different threads run in\n"
           "parallel; calls on one Segmenter from several threads take turns.")
      .def("reset", &PySegmenter::reset, py::call_guard<py::gil_scoped_release>(),  // may wait for a frame
           "Forgets the temporal window: the next frame starts a new stream.")
      .def_property_readonly("_params_json", &PySegmenter::params_json, "parameters as JSON text");

  py::class_<PyPipeline>(m, "Pipeline", "The C++ Pipeline; use clutterseg.Pipeline, which takes dicts and keywords.")
      .def(py::init<const std::string&>(), py::arg("params_json"),
           "params_json: parameters as JSON text (the form of `clutterseg --dump-config`)")
      .def("push", &PyPipeline::push, py::arg("depth"), py::arg("camera"),
           "push(depth, camera)\n\n"
           "Queues the next frame of the stream (arguments as Segmenter.segment). The array is read in place\n"
           "and kept alive until its Result is popped: do not write to it before. Blocks (GIL released)\n"
           "while `capacity` frames are in flight; raises as Segmenter.segment for a bad array or camera.")
      .def("pop", &PyPipeline::pop,
           "pop() -> Result\n\n"
           "The oldest pushed frame's Result, the same as Segmenter.segment gives for the same stream; waits\n"
           "for it (GIL released). Raises clutterseg.Error for that frame instead if it had no valid depth\n"
           "(the stream goes on without it), ValueError if nothing is in flight.")
      .def("reset", &PyPipeline::reset, py::call_guard<py::gil_scoped_release>(),
           "Forgets the temporal window and the object tracks once the frames in flight are through:\n"
           "the next pushed frame starts a new stream.")
      .def_property_readonly("in_flight", &PyPipeline::in_flight, "frames pushed and not yet popped")
      .def_property_readonly("capacity", &PyPipeline::capacity, "frames that may be in flight before push waits")
      .def_property_readonly("workers", &PyPipeline::workers, "worker threads (params threads; 0 = one per core)");
}

}  // namespace clutterseg::python
