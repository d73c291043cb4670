// The Python module prt._prt: the framework's stages, plug-ins and bake
// files with numpy arrays (docs/python.md).
#include <cstring>
#include <new>

#include "bindings.hpp"
#include "long_call.hpp"
#include "prt/error.hpp"

namespace prt::python {

PluginRegistry& registry() {
  // Never destroyed: plug-in objects held by Python may outlive the module's
  // statics at exit, and they keep their libraries through the registry.
  static auto* instance = new PluginRegistry(PluginRegistry::default_directories());
  return *instance;
}

Params params_from_kwargs(const py::dict& kwargs, const std::string& owner) {
  Params params(SourceLocation{owner});
  for (const auto& [key, item] : kwargs) {
    const std::string name = py::str(key);
    const SourceLocation where{owner + " keyword " + name};
    py::object value = py::reinterpret_borrow<py::object>(item);
    // numpy scalars (np.int64(4), np.float32(0.5), np.bool_) as Python's own
    if (py::hasattr(value, "item") && py::hasattr(value, "dtype") &&
        py::getattr(value, "ndim", py::int_(1)).cast<int>() == 0)
      value = value.attr("item")();
    if (py::isinstance<py::bool_>(value))
      params.set(name, value.cast<bool>(), where);
    else if (py::isinstance<py::int_>(value)) {
      std::int64_t integer = 0;
      try {
        integer = value.cast<std::int64_t>();
      } catch (const py::cast_error&) {
        throw Error(where, "parameter \"" + name + "\": " + std::string(py::str(value)) +
                               " does not fit in 64 bits");
      }
      params.set(name, integer, where);
    } else if (py::isinstance<py::float_>(value))
      params.set(name, value.cast<double>(), where);
    else if (py::isinstance<py::str>(value))
      params.set(name, value.cast<std::string>(), where);
    else if (py::isinstance<py::sequence>(value) || py::isinstance<py::array>(value)) {
      std::vector<double> list;
      for (const auto& item : value) {
        if (!py::isinstance<py::float_>(item) && !py::isinstance<py::int_>(item) &&
            !py::isinstance<py::array>(item))
          throw Error(where, "parameter \"" + name + "\": a list must hold numbers");
        list.push_back(item.cast<double>());
      }
      params.set(name, std::move(list), where);
    } else {
      throw Error(where, "parameter \"" + name + "\": cannot use a value of type " +
                             std::string(py::str(value.get_type().attr("__name__"))) +
                             " (give a bool, int, float, str or list of numbers)");
    }
  }
  return params;
}

py::dict params_to_dict(const Params& params) {
  py::dict out;
  for (const auto& [key, entry] : params.entries())
    std::visit([&](const auto& v) { out[py::str(key)] = py::cast(v); }, entry.value);
  return out;
}

namespace {

// Messages may quote a path's bytes that are not UTF-8: they are shown
// escaped (\xNN) rather than lost (PyErr_SetString gave an empty message).
void set_error(PyObject* type, const char* message) {
  PyObject* text = PyUnicode_DecodeUTF8(message, static_cast<Py_ssize_t>(std::strlen(message)),
                                        "backslashreplace");
  if (!text) {
    PyErr_Clear();
    text = PyUnicode_FromString("(a message that could not be decoded)");
  }
  PyErr_SetObject(type, text);
  Py_XDECREF(text);
}

}  // namespace

}  // namespace prt::python

using namespace prt;
using namespace prt::python;

PYBIND11_MODULE(_prt, m) {
  m.doc() = "PRT: precomputed radiance transfer (C++ core; use the package `prt`)";
  remember_main_thread();
  // Never freed: released after Python has gone, it would touch a dead interpreter.
  static auto& error = *new py::exception<Error>(m, "Error", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Interrupted&) {
      PyErr_SetNone(PyExc_KeyboardInterrupt);
    } catch (const Error& e) {
      set_error(error.ptr(), e.what());
    } catch (const std::filesystem::filesystem_error& e) {
      set_error(error.ptr(), filesystem_message(e).c_str());
    } catch (const std::bad_alloc&) {
      set_error(error.ptr(),
                "out of memory: an allocation failed in the call (the sizes asked for are "
                "larger than this machine can hold)");
    }
  });
  m.def("progress_callback", &progress_callback, "The current progress callback (or None).");
  m.def("set_progress_callback", &set_progress_callback, py::arg("callback"),
        "Receives every progress report as a dict (label, unit, done, total, rate, elapsed, "
        "eta, final); None: bars on standard error.");
  bind_types(m);
  bind_plugins(m);
  bind_pipeline(m);
}
