// Read-only attributes of a plain C++ struct, declared one line each. as_dict() and repr() walk the
// same list, so a field added to the struct (e.g. a tracking field of clutterseg::Object) is one line.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

namespace clutterseg::python {

namespace py = pybind11;

template <typename T, typename... Options>
class Fields {
 public:
  explicit Fields(py::class_<T, Options...>& cls) : cls_(cls), names_(std::make_shared<std::vector<std::string>>()) {}
  Fields(const Fields&) = delete;
  Fields& operator=(const Fields&) = delete;

  // `get(const T&)` returns the value (anything pybind11 converts); `doc` says what it is, with units.
  template <typename Get>
  Fields& add(const char* name, Get get, const char* doc) {
    cls_.def_property_readonly(name, [get](const T& t) { return get(t); }, doc);
    names_->push_back(name);
    return *this;
  }

  // Defines as_dict() and __repr__ over the fields added so far; call once, after the last add().
  void finish() {
    const auto names = names_;
    cls_.def(
        "as_dict",
        [names](const py::object& self) {
          py::dict d;
          for (const auto& n : *names) {
            py::object value = self.attr(n.c_str());
            if (py::hasattr(value, "as_dict")) value = value.attr("as_dict")();
            d[n.c_str()] = value;
          }
          return d;
        },
        "Every field as a dict (nested structs as dicts), in declaration order.");
    cls_.def("__repr__", [names](const py::object& self) {
      // Scalars only: arrays and nested structs would make a list of objects unreadable.
      std::string s = py::str(self.get_type().attr("__name__")).cast<std::string>() + "(";
      bool first = true;
      for (const auto& n : *names) {
        const py::object value = self.attr(n.c_str());
        if (!(py::isinstance<py::int_>(value) || py::isinstance<py::float_>(value) || py::isinstance<py::str>(value)))
          continue;
        s += (first ? "" : ", ") + n + "=" + py::repr(value).cast<std::string>();
        first = false;
      }
      return s + ")";
    });
  }

 private:
  py::class_<T, Options...>& cls_;
  std::shared_ptr<std::vector<std::string>> names_;
};

}  // namespace clutterseg::python
