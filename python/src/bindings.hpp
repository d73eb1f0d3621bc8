// The parts of the clutterseg extension module, one function each (module.cpp calls them in order).
#pragma once

#include <pybind11/pybind11.h>

namespace clutterseg::python {

namespace py = pybind11;

void bind_segmenter(py::module_& m);  // Camera, Segmenter, Result and what a result holds
void bind_data(py::module_& m);       // reading and writing frames, dataset frames, the metrics
void bind_synth(py::module_& m);      // the synthetic scene generator (submodule clutterseg.synth)

}  // namespace clutterseg::python
