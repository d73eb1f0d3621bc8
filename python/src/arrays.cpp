#include "arrays.hpp"

#include <cstdint>
#include <limits>

namespace clutterseg::python {

namespace {

// The NumPy dtype of an OpenCV depth (CV_8U ...), and the depth of a dtype (-1 for none).
py::dtype dtype_of(int cv_depth) {
  switch (cv_depth) {
    case CV_8U: return py::dtype::of<std::uint8_t>();
    case CV_8S: return py::dtype::of<std::int8_t>();
    case CV_16U: return py::dtype::of<std::uint16_t>();
    case CV_16S: return py::dtype::of<std::int16_t>();
    case CV_32S: return py::dtype::of<std::int32_t>();
    case CV_32F: return py::dtype::of<float>();
    case CV_64F: return py::dtype::of<double>();
  }
  throw std::logic_error("no NumPy dtype for OpenCV depth " + std::to_string(cv_depth));
}

// Equivalent types only: a byte-swapped '>u2' is not uint16 here.
int cv_depth_of(const py::handle& array) {
  if (py::isinstance<py::array_t<std::uint8_t, 0>>(array)) return CV_8U;
  if (py::isinstance<py::array_t<std::int8_t, 0>>(array)) return CV_8S;
  if (py::isinstance<py::array_t<std::uint16_t, 0>>(array)) return CV_16U;
  if (py::isinstance<py::array_t<std::int16_t, 0>>(array)) return CV_16S;
  if (py::isinstance<py::array_t<std::int32_t, 0>>(array)) return CV_32S;
  if (py::isinstance<py::array_t<float, 0>>(array)) return CV_32F;
  if (py::isinstance<py::array_t<double, 0>>(array)) return CV_64F;
  return -1;
}

std::string shape_text(const py::array& array) {
  std::string s = "(";
  for (py::ssize_t d = 0; d < array.ndim(); ++d) s += (d ? ", " : "") + std::to_string(array.shape(d));
  return s + (array.ndim() == 1 ? ",)" : ")");
}

std::string allowed_text(const std::vector<int>& types) {
  std::string s;
  for (size_t i = 0; i < types.size(); ++i) {
    s += i == 0 ? "" : i + 1 == types.size() ? " or " : ", ";
    s += py::str(dtype_of(types[i])).cast<std::string>();
  }
  return s;
}

py::array as_array(const py::handle& obj, const std::string& what) {
  if (!py::isinstance<py::array>(obj))
    throw py::type_error(what + ": expected a NumPy array, got " +
                         py::str(obj.get_type().attr("__name__")).cast<std::string>());
  return py::reinterpret_borrow<py::array>(obj);
}

// Shape checks shared by every 2-D input.
void check_2d(const py::array& array, const std::string& what) {
  if (array.ndim() != 2)
    throw py::value_error(what + ": expected a 2-D array (height x width), got shape " + shape_text(array));
  if (array.size() == 0) throw py::value_error(what + ": the array is empty (shape " + shape_text(array) + ")");
}

}  // namespace

std::string dtype_name(const py::handle& array) {
  return py::str(array.attr("dtype")).cast<std::string>();
}

cv::Mat view_2d(const py::handle& obj, const std::vector<int>& types, const std::string& what) {
  const py::array array = as_array(obj, what);
  const int depth = cv_depth_of(array);
  bool allowed = false;
  for (int t : types) allowed = allowed || t == depth;
  if (!allowed)
    throw py::type_error(what + ": dtype " + dtype_name(array) + " is not supported; expected " + allowed_text(types));
  check_2d(array, what);
  const auto rows = array.shape(0), cols = array.shape(1), item = array.itemsize();
  // NumPy may give any stride to a dimension of size 1; only strides that are used are checked.
  const py::ssize_t row_step = rows > 1 ? array.strides(0) : cols * item;
  const bool pixels_adjacent = cols == 1 || array.strides(1) == item;
  if (!pixels_adjacent || row_step < cols * item || row_step % item != 0)
    throw py::value_error(what + ": the array is not contiguous (strides (" + std::to_string(array.strides(0)) + ", " +
                          std::to_string(array.strides(1)) + ") for " + dtype_name(array) +
                          "); pass numpy.ascontiguousarray(" + what + ")");
  if (!(array.flags() & py::detail::npy_api::NPY_ARRAY_ALIGNED_))
    throw py::value_error(what + ": the array is not aligned in memory; pass numpy.ascontiguousarray(" + what + ")");
  return cv::Mat(static_cast<int>(rows), static_cast<int>(cols), CV_MAKETYPE(depth, 1),
                 const_cast<void*>(array.data()), static_cast<size_t>(row_step));
}

cv::Mat label_view(const py::handle& obj, const std::string& what) {
  const py::array array = as_array(obj, what);
  const int depth = cv_depth_of(array);
  if (depth == CV_32S || depth == CV_16U || depth == CV_8U) return view_2d(array, {depth}, what);
  const char kind = array.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw py::type_error(what + ": dtype " + dtype_name(array) + " is not supported; labels are integer ids");
  check_2d(array, what);
  const py::int_ lowest(std::numeric_limits<std::int32_t>::min()), highest(std::numeric_limits<std::int32_t>::max());
  if (array.attr("min")() < lowest || array.attr("max")() > highest)
    throw py::value_error(what + ": ids must fit in int32");
  const py::array converted = array.attr("astype")("int32", py::arg("order") = "C");
  return view_2d(converted, {CV_32S}, what).clone();  // `converted` dies with this call
}

py::array to_numpy(const cv::Mat& mat) {
  std::vector<py::ssize_t> shape = {mat.rows, mat.cols};
  std::vector<py::ssize_t> strides = {static_cast<py::ssize_t>(mat.step[0]), static_cast<py::ssize_t>(mat.elemSize())};
  if (mat.channels() > 1) {
    shape.push_back(mat.channels());
    strides.push_back(static_cast<py::ssize_t>(mat.elemSize1()));
  }
  if (mat.empty()) return py::array(dtype_of(mat.depth()), shape, strides);
  auto* owner = new cv::Mat(mat);  // shares the pixels; freed with the array
  const py::capsule base(owner, [](void* p) { delete static_cast<cv::Mat*>(p); });
  return py::array(dtype_of(mat.depth()), shape, strides, owner->data, base);
}

}  // namespace clutterseg::python
