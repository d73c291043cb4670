// Shared pieces of the Python module `prt` (module `prt._prt`; the package's
// Python files wrap it).
#pragma once
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "prt/params.hpp"
#include "prt/registry.hpp"

namespace prt::python {
namespace py = pybind11;

// The module's registry: the build's (or install's) plug-in folder and
// PRT_PLUGIN_PATH, plus the plug-ins registered from Python.
PluginRegistry& registry();

// Keyword arguments as plug-in parameters, each located as "keyword NAME"
// in messages; validated later against the plug-in's schema.
Params params_from_kwargs(const py::dict& kwargs, const std::string& owner);
// Validated parameters as a dict of Python values.
py::dict params_to_dict(const Params& params);

// A numpy view of `rows` x `cols` row-major data owned by `owner` (no copy).
template <class T>
py::array_t<T> view(const T* data, py::ssize_t rows, py::ssize_t cols, py::handle owner) {
  return py::array_t<T>(
      {rows, cols},
      {cols * static_cast<py::ssize_t>(sizeof(T)), static_cast<py::ssize_t>(sizeof(T))}, data,
      owner);
}

void bind_types(py::module_& m);
void bind_plugins(py::module_& m);
void bind_pipeline(py::module_& m);

}  // namespace prt::python
