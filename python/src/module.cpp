// clutterseg._clutterseg: the compiled part of the Python package; python/clutterseg/__init__.py
// re-exports it and adds the parameter handling and the evaluation loop.
#include <opencv2/core.hpp>

#include "bindings.hpp"
#include "clutterseg/types.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_clutterseg, m) {
  m.doc() = "clutterseg's C++ core (use the clutterseg package, not this module)";
  // Failures the core reports (files, their content): the same one-line message as the CLI's.
  static py::exception<clutterseg::Error> error(m, "Error", PyExc_RuntimeError);
  error.attr("__doc__") = "A failure reported by clutterseg's core: a one-line message naming the input and the problem.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const clutterseg::Error& e) {
      error(e.what());
    } catch (const cv::Exception& e) {  // OpenCV's own what() spans several lines
      error(("OpenCV: " + e.err + (e.func.empty() ? "" : " (in " + e.func + ")")).c_str());
    }
  });
  clutterseg::python::bind_segmenter(m);
  clutterseg::python::bind_data(m);
  clutterseg::python::bind_synth(m);
}
