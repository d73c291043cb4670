// Shared pieces of the Python module `prt` (module `prt._prt`; the package's
// Python files wrap it).
#pragma once
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include "prt/mesh.hpp"
#include "prt/params.hpp"
#include "prt/registry.hpp"
#include "prt/transfer.hpp"
#include "prt/transport.hpp"

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
// Read-only: the C++ side checked the data when it was made (indices in
// range, shapes), and a write through a view would skip those checks.
template <class T>
py::array_t<T> read_only(py::array_t<T> a) {
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

template <class T>
py::array_t<T> view(const T* data, py::ssize_t rows, py::ssize_t cols, py::handle owner) {
  return read_only(py::array_t<T>(
      {rows, cols},
      {cols * static_cast<py::ssize_t>(sizeof(T)), static_cast<py::ssize_t>(sizeof(T))}, data,
      owner));
}

// How Python says "overwrite" in output-file messages.
inline const char* kForceKeyword = "force=True";

// Rays traced for a scene, with what they depend on (the scene's folder,
// mesh, transport and material), so bake(traced=...) refuses rays of another.
struct Traced {
  TransportResult result;
  std::string key;
};

// Visibility bits unpacked: vertices x directions, one byte per bit (a copy).
py::array_t<std::uint8_t> visibility_array(const VisibilityBits& bits);

// Throws unless the signal has rows and columns and the mesh (if any) one
// vertex per row.
void check_signal_and_mesh(const TransferSignal& signal, const Mesh* mesh);

void bind_types(py::module_& m);
void bind_plugins(py::module_& m);
void bind_pipeline(py::module_& m);

}  // namespace prt::python
