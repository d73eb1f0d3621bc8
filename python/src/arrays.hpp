// NumPy arrays <-> cv::Mat without copying: a 2-D array becomes a Mat header on its memory, and a Mat
// becomes an array that keeps a reference-counted header of the Mat alive (a capsule), so neither way
// copies pixels.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace clutterseg::python {

namespace py = pybind11;

// A cv::Mat header on the memory of a 2-D array whose dtype is one of `types` (CV_16U, CV_32F, ...).
// Rows may be padded (a cropped view of a larger array works); pixels within a row must be adjacent.
// Anything else raises TypeError (not an array, other dtype) or ValueError (shape, empty, strides),
// naming `what`. The Mat is valid while `array` is alive.
cv::Mat view_2d(const py::handle& array, const std::vector<int>& types, const std::string& what);

// A label image for the metrics: int32, uint16 and uint8 arrays are viewed in place; other integer
// dtypes (NumPy's default int64) are converted to int32 (a copy), with an error for ids beyond int32.
cv::Mat label_view(const py::handle& array, const std::string& what);

// A NumPy array on the memory of `mat` (H x W, or H x W x C for C > 1 channels); the array owns a
// copy of the Mat header, so the pixels live as long as the array does.
py::array to_numpy(const cv::Mat& mat);

// The dtype name NumPy would print, for error messages.
std::string dtype_name(const py::handle& array);

}  // namespace clutterseg::python
